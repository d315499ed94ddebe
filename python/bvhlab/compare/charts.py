"""Charts of a comparison (matplotlib, PNG): frame and build time per method, nodes per depth."""
from __future__ import annotations

from pathlib import Path


def _plt():
    import matplotlib

    matplotlib.use("Agg")  # files only, no display
    import matplotlib.pyplot as plt

    return plt


def times_chart(rows: list[dict], path: Path, title: str) -> Path:
    plt = _plt()
    fig, axes = plt.subplots(1, 2, figsize=(9, 3.6))
    names = [r["method"] for r in rows]
    for ax, key, label in ((axes[0], "frame_ms", "frame time (ms)"), (axes[1], "build_ms", "build time (ms)")):
        values = [r[key] for r in rows]
        bars = ax.bar(names, values, color="#4c78a8")
        ax.bar_label(bars, fmt="%.0f", fontsize=8)
        ax.set_ylabel(label)
        ax.tick_params(axis="x", rotation=30)
    fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def nodes_per_depth_chart(rows: list[dict], path: Path, title: str) -> Path:
    plt = _plt()
    fig, ax = plt.subplots(figsize=(7, 3.8))
    for r in rows:
        ax.plot(range(len(r["nodes_per_depth"])), r["nodes_per_depth"], marker=".", label=r["method"])
    ax.set_yscale("log")
    ax.set_xlabel("depth (root = 0)")
    ax.set_ylabel("nodes")
    ax.set_title(title)
    ax.legend()
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
