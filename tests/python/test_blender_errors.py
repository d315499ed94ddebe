"""Issue 8, "errors that must be clear" in the add-on, through its operators under bpy: a NaN object
location and an infinite vertex name the object (Blender stores inf as 3.4e38, which must not pass
as a coordinate), a camera scaled to 0 blocks neither Build nor Export stats (they need no camera),
a scene at 1e12 exports without "camera position and look_at coincide", and Export stats writes
exactly the path it is given or refuses it."""

import json

import blender_checks  # noqa: F401  (import path for tests/blender)
import bpy  # noqa: E402
import harness  # before bpy
import numpy as np
import pytest

from bvhlab.blender import ExportError, SubstituteWarning, export_scene  # noqa: E402


@pytest.fixture(scope="module", autouse=True)
def addon_enabled():
    harness.enable_addon_from_source()


def error_report(operator, **kwargs) -> str:
    """The ERROR report of an operator (a script sees it as RuntimeError)."""
    with pytest.raises(RuntimeError) as caught:
        operator(**kwargs)
    return str(caught.value)


def test_nan_location_names_the_object():
    harness.boxes_scene()
    bpy.data.objects["Box B"].location.x = float("nan")
    message = error_report(bpy.ops.bvhlab.build)
    assert "object 'Box B'" in message and "not a number in world space" in message, message
    harness.boxes_scene()
    assert bpy.ops.bvhlab.build() == {"FINISHED"}  # Blender still works


@pytest.mark.parametrize("value", [float("inf"), 3e38, 2e12])
def test_a_vertex_beyond_the_range_names_the_object(value):
    harness.boxes_scene()
    bpy.data.objects["Box C"].data.vertices[2].co.y = value
    message = error_report(bpy.ops.bvhlab.build)
    assert "object 'Box C' reaches outside the supported coordinate range" in message, message
    with pytest.raises(ExportError, match="Box C"):
        export_scene(bpy.context)


def test_an_object_scaled_beyond_the_range_names_the_object():
    harness.boxes_scene()
    bpy.data.objects["Box A"].scale = (1e13, 1, 1)
    assert "object 'Box A' reaches outside" in error_report(bpy.ops.bvhlab.build)


def test_camera_scaled_to_zero_blocks_neither_build_nor_export_stats(tmp_path):
    harness.boxes_scene()
    bpy.context.scene.camera.scale = (0, 0, 0)
    assert bpy.ops.bvhlab.build() == {"FINISHED"}
    path = tmp_path / "stats.json"
    assert bpy.ops.bvhlab.export_stats(filepath=str(path)) == {"FINISHED"}
    assert json.loads(path.read_text())["stats"]["primitives"] == 36
    message = error_report(bpy.ops.bvhlab.render)  # a render does need it: say which and why
    assert "camera 'Camera'" in message and "orientation" in message, message


@pytest.mark.parametrize("with_camera", [True, False])
def test_a_scene_at_1e12_exports_and_builds(with_camera):
    harness.boxes_scene()
    for obj in bpy.context.scene.objects:
        if obj.type == "MESH" or (with_camera and obj.type in ("CAMERA", "LIGHT")):
            obj.location.x += 1e12
    if not with_camera:
        bpy.context.scene.camera = None
    bpy.context.view_layer.update()
    assert bpy.ops.bvhlab.build() == {"FINISHED"}
    if with_camera:
        exported = export_scene(bpy.context, require_camera=False)
    else:  # the default camera that frames the geometry, said as a warning
        with pytest.warns(SubstituteWarning, match="has no camera"):
            exported = export_scene(bpy.context, require_camera=False)
    position, look_at = np.float32(exported.camera.position), np.float32(exported.camera.look_at)
    assert np.any(position != look_at)  # distinct where the tracer computes, in float32


def test_export_stats_writes_the_path_given_or_refuses(tmp_path):
    harness.boxes_scene()
    (tmp_path / "folder").mkdir()
    assert "is a folder" in error_report(bpy.ops.bvhlab.export_stats, filepath=str(tmp_path / "folder"))
    assert "written as .json" in error_report(bpy.ops.bvhlab.export_stats, filepath=str(tmp_path / "stats.txt"))
    assert sorted(p.name for p in tmp_path.iterdir()) == ["folder"]  # nothing written, nothing renamed
    assert bpy.ops.bvhlab.export_stats(filepath=str(tmp_path / "named")) == {"FINISHED"}  # the browser's .json
    assert sorted(p.name for p in tmp_path.iterdir()) == ["folder", "named.csv", "named.json"]
