"""Charts of a comparison (matplotlib, PNG): frame and build time per method with their spreads,
nodes per depth, SAH cost per depth, and the leaf-size histogram."""

from __future__ import annotations

import io
import math
from pathlib import Path

from .._atomic import replacing


def _plt():
    import matplotlib

    matplotlib.use("Agg")  # files only, no display
    import matplotlib.pyplot as plt

    return plt


def value_label(v: float) -> str:
    """Three significant digits without exponents: 1234 → '1234', 12.34 → '12.3', 0.0123 → '0.0123'."""
    if not math.isfinite(v) or v == 0:
        return f"{v:g}"
    digits = max(0, 2 - int(math.floor(math.log10(abs(v)))))
    return f"{v:.{digits}f}"


def _save(fig, plt, path: Path) -> Path:
    with replacing(path) as f:  # whole or not at all
        f.write(_figure_bytes(fig, plt, Path(path).suffix[1:] or "png"))
    return path


def _figure_bytes(fig, plt, kind: str = "png") -> bytes:
    """The figure, laid out, in a file format's bytes (`kind`: png, svg, pdf); closed after."""
    try:
        fig.tight_layout()
        f = io.BytesIO()
        fig.savefig(f, format=kind, dpi=110)
    finally:
        plt.close(fig)
    return f.getvalue()


def times_chart(rows: list[dict], path: Path, title: str) -> Path:
    """Median frame and build time per method; the error bars span each median's interval."""
    plt = _plt()
    fig, axes = plt.subplots(1, 2, figsize=(9, 3.8))
    names = [r["method"] for r in rows]
    cpu = rows[0].get("frame_clock") == "cpu"
    frame = ("frame_cpu_ms", "frame, CPU time (ms)") if cpu else ("frame_ms", "frame time (ms)")
    build = ("build_cpu_ms", "build, CPU time (ms)") if "build_cpu_ms" in rows[0] else ("build_ms", "build time (ms)")
    for ax, (key, label) in zip(axes, (frame, build)):
        values = [r[key] for r in rows]
        lo = [r.get(f"{key}_lo", math.nan) for r in rows]
        hi = [r.get(f"{key}_hi", math.nan) for r in rows]
        errors = [
            [0 if math.isnan(a) else v - a for v, a in zip(values, lo)],
            [0 if math.isnan(b) else b - v for v, b in zip(values, hi)],
        ]
        bars = ax.bar(names, values, color="#4c78a8", yerr=errors, capsize=3, ecolor="#333333")
        ax.bar_label(bars, labels=[value_label(v) for v in values], fontsize=8, label_type="center", color="white")
        ax.set_ylabel(label)
        ax.tick_params(axis="x", rotation=30)
    fig.suptitle(title)
    return _save(fig, plt, path)


def _per_depth_chart(series: list[tuple[str, list[float]]], path: Path, title: str, ylabel: str, log: bool) -> Path:
    plt = _plt()
    fig, ax = plt.subplots(figsize=(7, 3.8))
    for name, values in series:
        ax.plot(range(len(values)), values, marker=".", label=name)
    if log:
        ax.set_yscale("log")
    ax.set_xlabel("depth (root = 0)")
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    ax.legend()
    ax.grid(alpha=0.3)
    return _save(fig, plt, path)


def nodes_per_depth_chart(rows: list[dict], path: Path, title: str) -> Path:
    return _per_depth_chart([(r["method"], r["nodes_per_depth"]) for r in rows], path, title, "nodes", True)


def sah_per_depth_chart(rows: list[dict], path: Path, title: str) -> Path:
    """Each depth's share of the SAH cost (Σ A(n)/A(R)·(1 or N)); the curves sum to the tree's cost."""
    series = [(f"{r['method']} (total {r['sah_cost']:.1f})", r["sah_cost_per_depth"]) for r in rows]
    return _per_depth_chart(series, path, title, "SAH cost at this depth", False)


def leaf_size_chart(rows: list[dict], path: Path, title: str) -> Path:
    """Leaves per primitive count, one bar group per leaf size (log scale)."""
    plt = _plt()
    fig, ax = plt.subplots(figsize=(7, 3.8))
    sizes = max(len(r["leaf_size_histogram"]) for r in rows)
    width = 0.8 / len(rows)
    for i, r in enumerate(rows):
        hist = r["leaf_size_histogram"]
        xs = [k + (i - (len(rows) - 1) / 2) * width for k in range(len(hist)) if hist[k]]
        ax.bar(xs, [h for h in hist if h], width, label=r["method"])
    ax.set_yscale("log")
    ax.set_xticks(range(1, sizes))
    ax.set_xlabel("primitives in the leaf")
    ax.set_ylabel("leaves")
    ax.set_title(title)
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3, axis="y")
    return _save(fig, plt, path)
