"""The frames of an animated `.blend` (issue 34's experiment, `bvhlab animate FILE.blend`): each frame
set in Blender and exported with the add-on's exporter (export_scene: modifiers, geometry nodes,
shape keys evaluated; Blender's instancing kept as instances of shared meshes)."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

from ..scene import Scene


def open_animation(path: Path) -> tuple[Callable[[int], Scene], range]:
    """Open `path` with bpy; returns (scene_at(frame), the file's frame range). `scene_at(k)` sets
    frame k and exports the visible scene as the add-on does."""
    path = Path(path)
    if not path.exists():
        raise FileNotFoundError(f"no such file: {path}")
    from .export import export_scene
    from .load import open_blend

    bpy = open_blend(path)
    scene = bpy.context.scene

    def scene_at(frame: int) -> Scene:
        scene.frame_set(frame)
        return export_scene(bpy.context, scope="visible")

    return scene_at, range(scene.frame_start, scene.frame_end + 1)
