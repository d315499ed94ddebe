"""Figures like the report's, rendered with the overlay pass (one PNG per method):
Figure 3, the five spheres after one split; Figure 4, all depths but the root; Figure 5, depths
8–9 of a high-poly mesh."""
from __future__ import annotations

from pathlib import Path

from ..bvh import build
from ..render import Renderer, save_png
from ..scene import Scene
from .measure import method_kwargs

FIGURES = {
    "figure3": ("the BVs after splitting the five spheres once", lambda height: (1, 1)),
    "figure4": ("the BVs at every depth but the root", lambda height: (1, max(1, height - 1))),
    "figure5": ("only the BVs at depths 8 and 9", lambda height: (8, 9)),
}


def render_figure(name: str, scene: Scene, labels: list[str], out: Path, renderer: Renderer,
                  width: int = 640, height: int = 480, line_width: float = 1.0) -> list[Path]:
    """One PNG per method: `<name>_<method>.png`."""
    _, depths_of = FIGURES[name]
    paths = []
    for label in labels:
        bvh = build(scene, axis="largest", max_leaf_size=1, **method_kwargs(label))  # the report's trees: one per leaf
        depths = depths_of(bvh.stats["height"])
        image, _ = renderer.render(scene, bvh, width, height, overlay_depth=depths, line_width=line_width)
        path = out / f"{name}_{label}.png"
        save_png(image, path)
        paths.append(path)
    return paths
