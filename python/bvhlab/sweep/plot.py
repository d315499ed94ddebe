"""The sweep's plot: SAH cost against build time, one panel per scene, one colour per method, and the
Pareto front (the settings no other setting beats on both) drawn through them."""

from __future__ import annotations

import math
from pathlib import Path

from .._atomic import replacing

PLOT = "sah_vs_build.png"
#: Panels a plot of the sweep draws at most, one a scene, the first scenes (the table and
#: summary.md hold them all): 600 scenes made two figures 70,000 pixels tall, 2 min 22 s at every
#: run, a rerun of nothing and after a Ctrl-C too (helper probe).
MAX_PANELS = 24


def pareto_front(points: list[tuple[float, float]]) -> list[tuple[float, float]]:
    """The points no other point beats on both coordinates (lower is better), by the first."""
    front: list[tuple[float, float]] = []
    for x, y in sorted(points):
        if not front or y < front[-1][1]:
            front.append((x, y))
    return front


def plot_sah_against_build_time(rows: list[dict], path: Path) -> Path | None:
    """The plot of the rows with status "ok" at `path`; None when there are none."""
    ok = [r for r in rows if r.get("status") == "ok"]
    if not ok:
        return None
    import matplotlib

    matplotlib.use("Agg")  # files only, no display
    import matplotlib.pyplot as plt

    every = sorted({r["scene"] for r in ok})
    scenes = every[:MAX_PANELS]
    methods = sorted({r["method"] for r in ok})
    colours = {m: plt.get_cmap("tab10")(i % 10) for i, m in enumerate(methods)}
    fig, axes = panel_grid(len(scenes), 3.6)
    for ax, scene in zip(axes.flat, scenes):
        mine = [r for r in ok if r["scene"] == scene]
        for method in methods:
            xs = [r["build_ms"] for r in mine if r["method"] == method]
            ys = [r["sah_cost"] for r in mine if r["method"] == method]
            if xs:
                ax.scatter(xs, ys, s=18, color=colours[method], label=method)
        front = pareto_front([(r["build_ms"], r["sah_cost"]) for r in mine])
        ax.plot(*zip(*front), color="0.4", lw=0.8, ls="--", drawstyle="steps-post", label="Pareto front")
        ax.set(title=scene, xlabel="build time (ms, one thread)", ylabel="SAH cost")
        times = [r["build_ms"] for r in mine if r["build_ms"] > 0]
        if times and max(times) > 20 * min(times):  # full sweeps next to LBVH: orders of magnitude apart
            ax.set_xscale("log")
        ax.legend(fontsize=7)
    return save_panels(fig, axes, len(scenes), path, len(every))


def panel_grid(panels: int, height: float):
    """A figure of `panels` panels, three to a row (matplotlib, drawing to files only)."""
    import matplotlib

    matplotlib.use("Agg")  # files only, no display
    import matplotlib.pyplot as plt

    cols = min(3, panels)
    rows = math.ceil(panels / cols)
    return plt.subplots(rows, cols, figsize=(4.5 * cols, height * rows), squeeze=False)


def save_panels(fig, axes, used: int, path: Path, scenes: int | None = None) -> Path:
    """Hides the grid's panels past the first `used`, writes the figure to `path` as PNG (whole or
    not at all) and closes it; where the sweep has more `scenes` than panels, says so on top."""
    import matplotlib.pyplot as plt

    for ax in list(axes.flat)[used:]:
        ax.set_visible(False)
    try:
        top = 1.0
        if scenes is not None and scenes > used:
            fig.suptitle(f"the first {used} of {scenes} scenes (results.csv and summary.md have them all)", fontsize=9)
            top = 1.0 - 0.3 / fig.get_figheight()
        fig.tight_layout(rect=(0, 0, 1, top))
        with replacing(path) as f:
            fig.savefig(f, format="png", dpi=100)
    finally:
        plt.close(fig)
    return path
