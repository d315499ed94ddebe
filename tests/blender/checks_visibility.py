"""Ray visibility as Cycles renders it (Object ▸ Visibility ▸ Ray Visibility): an object hidden from
camera rays is passed through by them; an instance is seen by a ray only where both it and the
object instancing it let that ray see them (Cycles' blender/object.cpp ands the two). Checked
against Cycles' Depth pass (1 sample through the pixel centre) on F12 with each backend and in
the Rendered viewport's camera view; the other flags against the exported materials. Before,
every object was seen by every ray (a note said so)."""

from __future__ import annotations

import bpy
import numpy as np
from checks_cameras import camera_scene, compare_depth, cycles_depth, engine_depth, viewport_depth, vulkan_backends
from checks_engine import _last_final

from bvhlab import Rays
from bvhlab.blender import export_scene


def visibility_scene():
    """camera_scene with Box A hidden from the camera, 'Crate 1' (an instancer: both its parts)
    too, 'Crate part 0' (instanced: in both crates), and Box B hidden from shadow rays and
    reflections."""
    scene = camera_scene((80, 60))
    objects = bpy.data.objects
    objects["Box A"].visible_camera = False
    objects["Crate 1"].visible_camera = False
    objects["Crate part 0"].visible_camera = False
    objects["Box B"].visible_shadow = objects["Box B"].visible_glossy = False
    bpy.context.view_layer.update()
    return scene


def check_ray_visibility_against_cycles(tmp_dir) -> None:
    camera_scene((80, 60))
    seen_by_all = cycles_depth(tmp_dir, "seen_by_all")
    scene = visibility_scene()
    reference = cycles_depth(tmp_dir, "visibility")
    changed = int((np.abs(seen_by_all - reference) > 1e-3 * seen_by_all).sum())
    assert changed > 150, changed  # the flags show in Cycles' image
    lines = []
    for backend in vulkan_backends():
        lines.append(compare_depth(engine_depth(tmp_dir, "visibility", backend), reference, f"F12 {backend}"))
        assert not _last_final(scene)["unrendered"], _last_final(scene)["unrendered"]
    lines.append(compare_depth(viewport_depth(scene), reference, "viewport"))
    exported = export_scene(bpy.context)
    hidden = {m.hidden_from for m in exported.materials}
    assert Rays.CAMERA in hidden and Rays.SHADOW | Rays.REFLECTION in hidden, hidden
    print(f"ray visibility against Cycles ({changed} pixels the flags change):\n  " + "\n  ".join(lines))
