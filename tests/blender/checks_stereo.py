"""Stereoscopy and multi-view renders (Output ▸ Stereoscopy): each eye framed as Blender frames it
for Cycles — the eyes' interocular offset and the three convergence modes (off-axis: a lens shift;
parallel; toe-in: the eyes turned) — checked eye by eye against Cycles' Depth pass as the other
cameras are (checks_cameras.compare_depth); and a multi-view render's views each through its own
camera (the camera of the view's suffix). Before, the engine rendered one view and the right eye
of a stereo render came out empty."""

from __future__ import annotations

import bpy
import exr
import numpy as np
from checks_cameras import camera_scene, compare_depth, use_cycles_reference, use_engine, vulkan_backends
from checks_engine import ENGINE, _last_final

from bvhlab.blender.compat import use_multilayer_exr

#: Output ▸ Stereoscopy's convergence modes (the camera's Stereoscopy panel).
MODES = ("OFFAXIS", "PARALLEL", "TOE")
#: The eyes' pivot each mode is checked with: both eyes off the camera, or the right one on it.
PIVOTS = {"OFFAXIS": "CENTER", "PARALLEL": "RIGHT", "TOE": "CENTER"}


def views_depth(tmp_dir, name: str) -> dict[str, np.ndarray]:
    """views_pass of the Depth pass."""
    return views_pass(tmp_dir, name, "Depth.Z")


def views_pass(tmp_dir, name: str, channel: str) -> dict[str, np.ndarray]:
    """F12 written as one multilayer EXR per view (Output ▸ Views Format Individual: the view's
    file suffix after `name`), each view's `channel` ("Depth.Z", "Combined.R") read back: {view
    name: top-row-first float32 (h, w)}. (The Render Result of several views is not saved by
    Image.save_render in the background.)"""
    scene = bpy.context.scene
    settings = scene.render.image_settings
    use_multilayer_exr(settings)
    settings.exr_codec, settings.color_depth, settings.views_format = "NONE", "32", "INDIVIDUAL"
    scene.render.filepath = str(tmp_dir / name)
    assert bpy.ops.render.render(write_still=True) == {"FINISHED"}
    layer = bpy.context.view_layer.name
    out = {}
    for view in scene.render.views:
        if view.use:
            path = tmp_dir / f"{name}{view.file_suffix}.exr"
            assert path.is_file(), f"view {view.name} was not written: {sorted(p.name for p in tmp_dir.iterdir())}"
            out[view.name] = exr.read_exr(path)[f"{layer}.{channel}"]
    return out


def _render(tmp_dir, name: str, engine: str, backend: str = "cpu") -> dict[str, np.ndarray]:
    scene = bpy.context.scene
    if engine == "CYCLES":
        use_cycles_reference(scene)
    else:
        use_engine(scene, backend)
    return views_depth(tmp_dir, f"{name}_{engine}_{backend}")


def _compare_views(tmp_dir, name: str) -> list[str]:
    """Each view on each backend against Cycles'; the views must differ from each other."""
    cycles = _render(tmp_dir, name, "CYCLES")
    assert len(cycles) >= 2, f"{name}: Cycles rendered {sorted(cycles)}"
    lines = []
    for backend in vulkan_backends():
        ours = _render(tmp_dir, name, ENGINE, backend)
        assert sorted(ours) == sorted(cycles), f"{name} {backend}: views {sorted(ours)}, Cycles {sorted(cycles)}"
        # Last Render's record: every view traced, their times added (it kept the last view's)
        record = _last_final(bpy.context.scene)
        assert sorted(record["views"]) == sorted(cycles), record["views"]
        for view, depth in ours.items():
            lines.append(compare_depth(depth, cycles[view], f"{name} {view} F12 {backend}"))
        first, *others = ours.values()
        for other in others:
            apart = (np.abs(other - first) > 1e-3 * np.minimum(other, first)).mean()
            assert apart > 0.05, f"{name} {backend}: the views are alike ({apart:.3f} of the pixels differ)"
    return lines


def check_stereo_eyes_against_cycles(tmp_dir, mode: str) -> None:
    """Stereo 3D with a wide interocular distance and a near convergence plane, in `mode`, the
    eyes about the pivot PIVOTS[mode] (the left eye, Blender's default pivot, is the camera's own
    view: a check of it alone passed when the engine rendered one view)."""
    scene = camera_scene()
    scene.render.use_multiview, scene.render.views_format = True, "STEREO_3D"
    stereo = scene.camera.data.stereo
    stereo.convergence_mode, stereo.interocular_distance, stereo.convergence_distance = mode, 0.5, 4.0
    # the pivot: the eyes about the camera (with Blender's default, Left, the left eye is the camera)
    stereo.pivot = PIVOTS[mode]
    bpy.context.view_layer.update()
    print("stereo eyes against Cycles:\n  " + "\n  ".join(_compare_views(tmp_dir, f"stereo_{mode.lower()}")))


def check_multiview_cameras_against_cycles(tmp_dir) -> None:
    """Multi-view: views "left" and "right" renamed to suffixes _A and _B, the scene camera
    "Camera_A", and "Camera_B" another camera (moved, another focal length): each view through its
    own camera's matrix and lens, as in Cycles."""
    scene = camera_scene()
    render = scene.render
    render.use_multiview, render.views_format = True, "MULTIVIEW"
    left, right = render.views["left"], render.views["right"]
    left.camera_suffix, right.camera_suffix = "_A", "_B"
    camera = scene.camera
    camera.name = "Camera_A"
    other = camera.copy()
    other.data = camera.data.copy()
    other.name = "Camera_B"
    scene.collection.objects.link(other)
    other.location.x += 0.6
    other.data.lens = 40
    bpy.context.view_layer.update()
    print("multi-view cameras against Cycles:\n  " + "\n  ".join(_compare_views(tmp_dir, "multiview")))
