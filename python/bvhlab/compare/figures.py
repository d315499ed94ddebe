"""Figures like the report's, rendered with the overlay pass (one PNG per method):
Figure 3, the five spheres after one split; Figure 4, all depths but the root; Figure 5, depths
8–9 of a model of over 700,000 triangles."""

from __future__ import annotations

import importlib.util
from pathlib import Path

from .. import legend
from ..bvh import build
from ..library import bundled_dir, load_scene
from ..png import save_png
from ..render import Renderer
from ..scene import Scene
from .measure import build_settings, render_frame

FIGURES = {
    "figure3": ("the BVs after splitting the five spheres once", lambda height: (1, 1)),
    "figure4": ("the BVs at every depth but the root", lambda height: (1, max(1, height - 1))),
    "figure5": ("only the BVs at depths 8 and 9", lambda height: (8, 9)),
}


def _bundled_blend_readable() -> bool:
    return bundled_dir() is not None and importlib.util.find_spec("bpy") is not None


def five_spheres_scene() -> tuple[Scene, str]:
    return load_scene("five_spheres" if _bundled_blend_readable() else "gen:five_spheres")


def figure5_scene() -> tuple[Scene, str]:
    """The report's Figure 5 model has over 700,000 triangles: the bundled Suzanne at subdivision
    level 5 (1,007,628) where Blender's bpy can read it, else a generated 1M-triangle knot."""
    return load_scene("suzanne_1m" if _bundled_blend_readable() else "gen:knot_1m")


def render_figure(
    name: str,
    scene: Scene,
    labels: list[str],
    out: Path,
    renderer: Renderer,
    width: int = 640,
    height: int = 480,
    line_width: float = 1.0,
) -> list[Path]:
    """One PNG per method: `<name>_<method>.png`, trees built with the report's settings, with the
    legend of the boxes' depth colours under the picture."""
    _, depths_of = FIGURES[name]
    paths = []
    for label in labels:
        bvh = build(scene, **{**build_settings(label), "threads": 0})  # the tree does not depend on threads
        depths = depths_of(bvh.stats["height"])
        image, *_ = render_frame(renderer, scene, bvh, width, height, overlay_depth=depths, line_width=line_width)
        image = legend.below(image, legend.depth_legend(width, range(depths[0], depths[1] + 1)))
        path = out / f"{name}_{label}.png"
        save_png(image, path)
        paths.append(path)
    return paths
