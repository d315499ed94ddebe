"""Ray visibility as Cycles renders it (Object ▸ Visibility ▸ Ray Visibility): an object hidden from
camera rays is passed through by them; an instance is seen by a ray only where both it and the
object instancing it let that ray see them (Cycles' blender/object.cpp ands the two); an object in
an Indirect Only collection is hidden from camera rays (as Cycles clears its camera visibility). Checked
against Cycles' Depth pass (1 sample through the pixel centre) on F12 with each backend and in
the Rendered viewport's camera view; the other flags against the exported materials. Before,
every object was seen by every ray (a note said so)."""

from __future__ import annotations

import bpy
import harness
import numpy as np
from checks_cameras import camera_scene, compare_depth, cycles_depth, engine_depth, viewport_depth, vulkan_backends
from checks_engine import _last_final

from bvhlab import Rays
from bvhlab.blender import export_scene


def visibility_scene():
    """camera_scene with a box in a collection; `hide` sets the flags (and back)."""
    scene = camera_scene((80, 60))
    indirect = bpy.data.collections.new("Indirect")
    scene.collection.children.link(indirect)
    box = harness.add_box("Indirect box", (-0.2, -2.5, 0.4), size=0.6)
    scene.collection.objects.unlink(box)
    indirect.objects.link(box)
    bpy.context.view_layer.update()
    return scene


def hide(on: bool) -> None:
    """Box A hidden from the camera, 'Crate 1' (an instancer: both its parts) too, 'Crate part 0'
    (instanced: in both crates), the box in an Indirect Only collection, and Box B hidden from
    shadow rays and reflections; or none of them."""
    objects = bpy.data.objects
    for name in ("Box A", "Crate 1", "Crate part 0"):
        objects[name].visible_camera = not on
    objects["Box B"].visible_shadow = objects["Box B"].visible_glossy = not on
    bpy.context.view_layer.layer_collection.children["Indirect"].indirect_only = on
    bpy.context.view_layer.update()


def check_ray_visibility_against_cycles(tmp_dir) -> None:
    scene = visibility_scene()
    seen_by_all = cycles_depth(tmp_dir, "seen_by_all")
    hide(True)
    reference = cycles_depth(tmp_dir, "visibility")
    changed = np.abs(seen_by_all - reference) > 1e-3 * seen_by_all
    assert changed.sum() > 250, changed.sum()  # the flags show in Cycles' image
    hide(False)
    bpy.context.view_layer.layer_collection.children["Indirect"].indirect_only = True  # alone: the box's
    bpy.context.view_layer.update()
    box = np.abs(cycles_depth(tmp_dir, "indirect") - seen_by_all) > 1e-3 * seen_by_all
    assert box.sum() > 20, box.sum()
    hide(True)
    lines = []
    for backend in vulkan_backends():
        lines.append(compare_depth(engine_depth(tmp_dir, "visibility", backend), reference, f"F12 {backend}"))
        assert not _last_final(scene)["unrendered"], _last_final(scene)["unrendered"]
    lines.append(compare_depth(viewport_depth(scene), reference, "viewport"))
    exported = export_scene(bpy.context)
    hidden = {m.hidden_from for m in exported.materials}
    assert Rays.CAMERA in hidden and Rays.SHADOW | Rays.REFLECTION in hidden, hidden
    print(
        f"ray visibility against Cycles ({changed.sum()} pixels the flags change, {box.sum()} Indirect Only):\n  "
        + "\n  ".join(lines)
    )
