"""The sweep's summary: each cell beside the cell of the baseline method with the same scene and
otherwise the same settings (SAH cost and Mrays/s as ratios to it), as a Markdown table
(DIR/summary.md) and a plot of the Mrays/s ratios, one panel per scene (DIR/mrays_vs_baseline.png)."""

from __future__ import annotations

from pathlib import Path

from .._atomic import write_text
from . import plot as _plots  # its MAX_PANELS read at each plot (tests change it)
from .plot import panel_grid, save_panels

SUMMARY, RATIO_PLOT = "summary.md", "mrays_vs_baseline.png"
#: Setting columns a label names when they vary over the grid (method always).
#: (Every setting of the grid: the seed and the SBVH settings left out, three seeds' rows were one
#: label, each divided by the last seed's baseline.)
_LABELLED = (
    *("bins", "bin_bounds", "axis", "max_leaf_size", "sah_block", "seed"),
    *("sbvh_alpha", "sbvh_budget", "sbvh_unsplit", "traversal"),
)
_SHORT = {
    **{"bins": "b", "max_leaf_size": "leaf", "sah_block": "block", "bin_bounds": "", "axis": "", "traversal": ""},
    **{"seed": "seed", "sbvh_alpha": "α", "sbvh_budget": "budget", "sbvh_unsplit": "unsplit"},
}


def _varying(rows: list[dict]) -> list[str]:
    """The settings (_LABELLED) that take more than one value over `rows`."""
    return [c for c in _LABELLED if len({r.get(c) for r in rows}) > 1]


def _by_method(rows: list[dict]) -> dict[str, list[dict]]:
    out: dict[str, list[dict]] = {}
    for r in rows:
        out.setdefault(r["method"], []).append(r)
    return out


def setting_labels(rows: list[dict], planned: list[dict] | None = None) -> dict[str, str]:
    """A short label for each row's setting ('sah b32 leaf4'): its method and the settings that
    vary over its method's cells (the `planned` ones, every cell of the grid, run or not; else
    `rows`), keyed by the row's key (bins only where a method's cells take several: the grid's
    method = ["median", "sah12", "sah32"] labelled every median cell "b12")."""
    varying = {method: _varying(of) for method, of in _by_method(planned or rows).items()}
    return {
        r["key"]: " ".join([r["method"], *(f"{_SHORT[c]}{r.get(c)}" for c in varying.get(r["method"], []))])
        for r in rows
    }


def baseline_pairs(
    rows: list[dict], baseline: str, planned: list[dict] | None = None
) -> list[tuple[dict, dict | None]]:
    """Each ok row with the ok row of method `baseline` for the same scene and the same settings of
    those the baseline's cells vary in (None where the grid has none, or that cell failed or has not
    run). The cells are the `planned` ones (every cell of the grid: a table the sweep stopped in
    lacks some, and a setting the baseline varies in then looked fixed, so leaf-4 cells were divided
    by a leaf-2 baseline; review), else `rows`. The grid is a product, so the baseline holds one
    value of a setting only where every method does, or where the setting is a method label's (the
    bins of "sah32"): those are not matched (sah32's cells had no median cell of 32 bins)."""
    matched = _varying([r for r in planned or rows if r["method"] == baseline])

    def others(row: dict) -> tuple:
        return (row["scene_hash"], *(row.get(c) for c in matched))

    ok = [r for r in rows if r.get("status") == "ok"]
    bases = {others(r): r for r in ok if r["method"] == baseline}
    return [(r, bases.get(others(r))) for r in ok]


def _ratio(value, base) -> float | None:
    return value / base if base and value is not None else None


def summary_table(rows: list[dict], baseline: str, planned: list[dict] | None = None) -> str:
    """The Markdown table: scene, setting, SAH cost, ÷ baseline, build ms, Mrays/s, ÷ baseline;
    headed by how many of the `planned` cells (Cell.columns of every cell) it lacks, where it lacks
    some (a sweep stopped)."""
    labels = setting_labels(rows, planned)
    missing = []
    if planned is not None and len(rows) < len(planned):
        stopped = "the sweep was stopped; the same command runs the rest"
        missing = [f"**Incomplete: {len(rows)} of {len(planned)} cells** ({stopped}).", ""]
    lines = [
        *missing,
        f"| scene | setting | SAH cost | SAH ÷ {baseline} | build ms | Mrays/s | Mrays/s ÷ {baseline} |",
        "|---|---|---|---|---|---|---|",
    ]
    for row, base in baseline_pairs(rows, baseline, planned):
        sah = _ratio(row["sah_cost"], base and base["sah_cost"])
        speed = _ratio(row["mrays_per_s"], base and base["mrays_per_s"])
        lines.append(
            f"| {_cell(row['scene'])} | {_cell(labels[row['key']])} | {row['sah_cost']:.1f} | {_fmt(sah)} | "
            f"{row['build_ms']:.1f} | {row['mrays_per_s']:.2f} | {_fmt(speed)} |"
        )
    failed = [r for r in rows if r.get("status") != "ok"]
    if failed:
        lines.append("")
        lines.extend(f"- {r['scene']} {labels[r['key']]}: {r.get('error')}" for r in failed)
    return "\n".join(lines) + "\n"


def _cell(text: str) -> str:
    """Text for a Markdown table cell: a "|" in a scene's name (a file "left|right.obj") split the
    row into one cell more, and every figure stood under the wrong heading (probe)."""
    return str(text).replace("\\", "\\\\").replace("|", "\\|").replace("\n", " ")


def _fmt(ratio: float | None) -> str:
    return "–" if ratio is None else f"{ratio:.2f}"


def write_summary(
    rows: list[dict], baseline: str, out: Path, plot: bool = True, planned: list[dict] | None = None
) -> list[Path]:
    """summary.md (saying so where it lacks some of the `planned` cells: Cell.columns of every cell
    of the grid), and (with `plot`) the ratio plot when any cell has a baseline to divide by (where
    none has, the runner removes an earlier run's, which stood beside the new table showing other
    cells)."""
    files = [write_text(out / SUMMARY, summary_table(rows, baseline, planned))]
    pairs = [(r, b) for r, b in baseline_pairs(rows, baseline, planned) if b is not None]
    if plot and pairs:
        files.append(_plot_ratios(pairs, setting_labels(rows, planned), baseline, out / RATIO_PLOT))
    return files


def _plot_ratios(pairs: list[tuple[dict, dict]], labels: dict[str, str], baseline: str, path: Path) -> Path:
    every = list(dict.fromkeys(r["scene"] for r, _ in pairs))
    scenes = every[: _plots.MAX_PANELS]
    most = max(sum(r["scene"] == scene for r, _ in pairs) for scene in scenes)
    # a bar's label a line of 7-point text: 63 settings in a fixed 3.4-inch panel printed over each other
    fig, axes = panel_grid(len(scenes), max(3.4, 0.8 + 0.14 * most))
    for ax, scene in zip(axes.flat, scenes):
        mine = [(r, b) for r, b in pairs if r["scene"] == scene]
        ratios = [r["mrays_per_s"] / b["mrays_per_s"] for r, b in mine]
        ax.barh(range(len(mine)), ratios, color=["0.55" if r["method"] == baseline else "tab:blue" for r, _ in mine])
        ax.set_yticks(range(len(mine)), [labels[r["key"]] for r, _ in mine], fontsize=7)
        ax.axvline(1.0, color="0.3", lw=0.8)
        ax.invert_yaxis()
        ax.set(title=scene, xlabel=f"Mrays/s ÷ {baseline} (higher is faster)")
    return save_panels(fig, axes, len(scenes), path, len(every))
