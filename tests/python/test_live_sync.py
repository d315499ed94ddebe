"""LiveScene kept across syncs (the Rendered viewport's view_update, F12 with Persistent Data),
under bpy 4.2, against a fresh LiveScene of the same depsgraph after each change (a probe,
2026-12-05): edits made while a sync fails are read once it succeeds again; a sphere renamed to
a deleted sphere's name keeps its own size."""

import warnings

import blender_checks  # noqa: F401  (import path for the shared checks)
import bpy  # noqa: E402  (after harness)
import harness  # before bpy
import numpy as np
import pytest

from bvhlab.blender import ExportError, LiveScene  # noqa: E402
from bvhlab.blender.sphere import SPHERE_PROPERTY  # noqa: E402


@pytest.fixture()
def viewport():
    """A LiveScene synced from every depsgraph update, as RenderEngine.view_update syncs it; yields
    it with the errors its syncs raised."""
    harness.empty_scene()
    harness.add_camera((0, -15, 0), (0, 0, 0))
    live = LiveScene("visible", require_camera=False, allow_empty=True)
    errors = []

    def view_update(scene, depsgraph):
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                live.sync(depsgraph, scene, depsgraph.view_layer)
        except ExportError as error:
            errors.append(str(error))

    bpy.app.handlers.depsgraph_update_post.append(view_update)
    try:
        yield live, errors
    finally:
        bpy.app.handlers.depsgraph_update_post.remove(view_update)


def fresh_scene():
    live = LiveScene("visible", require_camera=False, allow_empty=True)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        live.sync(bpy.context.evaluated_depsgraph_get())
    return live.scene


def test_edits_made_while_a_sync_fails_are_read_when_it_succeeds(viewport):
    """The updates a failed sync was told of are not told again: they were lost (A's vertices and
    material kept their state from before the error, until A changed again)."""
    live, errors = viewport
    a, b = harness.add_box("A", (-2, 0, 0)), harness.add_box("B", (2, 0, 0))
    material = bpy.data.materials.new("M")
    material.diffuse_color = (1, 0, 0, 1)
    a.data.materials.append(material)
    bpy.context.view_layer.update()
    b.location.x = 1e13  # out of range: the sync fails
    bpy.context.view_layer.update()
    assert errors and "outside the supported coordinate range" in errors[-1], errors
    for v in a.data.vertices:
        v.co.z += 3
    a.data.update()
    material.diffuse_color = (0, 0, 1, 1)
    bpy.context.view_layer.update()
    b.location.x = 2
    bpy.context.view_layer.update()
    want = fresh_scene()
    assert live.scene.flattened().triangles[:, :, 2].max() == want.flattened().triangles[:, :, 2].max() > 3
    assert [m.color for m in live.scene.materials] == [m.color for m in want.materials]
    assert any(m.color == (0.0, 0.0, 1.0) for m in live.scene.materials)


def test_a_sphere_renamed_to_a_deleted_spheres_name_keeps_its_size(viewport):
    live, _ = viewport
    for name, radius, x in (("A", 0.5, -2.0), ("B", 1.5, 3.0)):
        bpy.ops.mesh.primitive_uv_sphere_add(radius=radius, location=(x, 0, 0))
        obj = bpy.context.active_object
        obj.name = name
        obj[SPHERE_PROPERTY] = True
    bpy.context.view_layer.update()
    assert sorted(live.scene.spheres[:, 3].round(3)) == [0.5, 1.5]
    bpy.data.objects.remove(bpy.data.objects["A"])
    bpy.data.objects["B"].name = "A"
    bpy.context.view_layer.update()
    np.testing.assert_allclose(live.scene.spheres, fresh_scene().spheres)
    assert live.scene.spheres[0, 3] == pytest.approx(1.5, rel=1e-3)
