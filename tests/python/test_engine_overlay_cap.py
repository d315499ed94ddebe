"""F12 and the Rendered viewport say when the BLAS boxes their overlay pass traces hit the cap
(issue 34), as the sidebar says it under its boxes, under bpy 4.2. The oracle counts the boxes from
a fresh build of the exported scene: every instance shows one mesh, so the instances whose BLAS
boxes fit are (cap - TLAS boxes shown) // BLAS boxes per instance; the boxes the tracers are given
(two_level_boxes) hold exactly that many instances."""

import re
from dataclasses import replace

import blender_checks  # noqa: F401  (import path for the shared checks)
import bpy  # noqa: E402  (after harness)
import checks_engine  # noqa: E402
import checks_engine_viewport as viewport_checks  # noqa: E402
import harness  # before bpy
import numpy as np
import pytest

import bvhlab  # noqa: E402
from bvhlab.blender import export_scene  # noqa: E402
from bvhlab.overlay_levels import MAX_OVERLAY_BOXES, two_level_boxes  # noqa: E402

DEPTHS = (0, 63)  # every node


@pytest.fixture(scope="module", autouse=True)
def addon_enabled():
    harness.enable_addon_from_source()


def grid_of_monkeys(count: int):
    """Suzanne (968 triangles) in a collection instanced by `count` empties in a grid."""
    scene = harness.empty_scene((16, 12))
    harness.add_camera((20.0, -60.0, 40.0), (60.0, 60.0, 0.0), lens=20)
    harness.add_point_light((20.0, -5.0, 30.0))
    source = bpy.data.collections.new("Source")
    bpy.ops.mesh.primitive_monkey_add()
    monkey = bpy.context.active_object
    bpy.context.scene.collection.objects.unlink(monkey)
    source.objects.link(monkey)
    for i in range(count):
        empty = bpy.data.objects.new(f"Instance {i}", None)
        empty.instance_type, empty.instance_collection = "COLLECTION", source
        bpy.context.scene.collection.objects.link(empty)
        empty.location = (3.0 * (i % 40), 3.0 * (i // 40), 0.0)
    bpy.context.view_layer.update()
    return scene


def expected_shown(level: str) -> tuple[int, int]:
    """(instances with their BLAS boxes shown, instances), counted from a fresh build's arrays."""
    bvh = bvhlab.build(export_scene(bpy.context, require_camera=False))
    assert isinstance(bvh, bvhlab.InstancedBvh)
    mesh_of = np.asarray(bvh.instances[0])
    assert len(set(mesh_of.tolist())) == 1  # one mesh shown by every instance
    per_instance = len(bvh.meshes[int(mesh_of[0])].depths)  # DEPTHS spans every node
    tlas = len(bvh.tlas_node_data().depth) if level == "both" else 0
    instances = len(mesh_of)
    shown = min(instances, (MAX_OVERLAY_BOXES - tlas) // per_instance)
    boxes = two_level_boxes(bvh, level, *DEPTHS)
    assert len(np.unique(boxes.instance[boxes.instance >= 0])) == shown and len(boxes.lo) <= MAX_OVERLAY_BOXES
    return shown, instances


def said(note: str) -> tuple[int, int]:
    """(shown, instances) from a note 'BLAS boxes of 123 of 800 instances (...)'."""
    found = re.search(r"BLAS boxes of ([\d,]+) of ([\d,]+) instances", note)
    assert found, note
    return int(found[1].replace(",", "")), int(found[2].replace(",", ""))


def test_f12_says_when_the_blas_boxes_hit_the_cap(tmp_path):
    scene = grid_of_monkeys(800)
    checks_engine.use_engine(
        scene, backend="cpu", render_supersampling=1, render_overlay=True, overlay_depth_min=0, overlay_depth_max=63
    )
    for level in ("blas", "both"):
        scene.bvhlab.overlay_level = level
        assert bpy.ops.render.render() == {"FINISHED"}
        note = checks_engine._last_final(scene)["overlay_note"]
        shown, instances = expected_shown(level)
        assert shown < instances == 800, (shown, instances)
        assert said(note) == (shown, instances), note
    scene.bvhlab.overlay_level = "tlas"  # every TLAS box is traced: nothing to say
    assert bpy.ops.render.render() == {"FINISHED"}
    assert checks_engine._last_final(scene)["overlay_note"] == ""


def test_f12_says_nothing_below_the_cap(tmp_path):
    scene = grid_of_monkeys(20)
    checks_engine.use_engine(
        scene, backend="cpu", render_supersampling=1, render_overlay=True, overlay_depth_min=0, overlay_depth_max=63
    )
    scene.bvhlab.overlay_level = "both"
    assert bpy.ops.render.render() == {"FINISHED"}
    assert expected_shown("both") == (20, 20)
    assert checks_engine._last_final(scene)["overlay_note"] == ""


def test_the_rendered_viewport_says_when_the_blas_boxes_hit_the_cap():
    scene = grid_of_monkeys(800)
    session, request, _ = viewport_checks._session_for(scene, 16, 12, samples_per_axis=1, overlay=DEPTHS)
    try:
        session.request(replace(request, settings=request.settings.replace(overlay_level="blas")))
        frame = viewport_checks._wait(
            lambda: (
                f if (f := session.latest_frame()) is not None and f.request.settings.overlay_level == "blas" else None
            )
        )
        shown, instances = expected_shown("blas")
        assert shown < instances
        assert said(frame.timings["overlay_note"]) == (shown, instances)
        viewport_checks._wait(lambda: frame.timings["overlay_note"] in session.status(), what="the status line")
    finally:
        session.close()
