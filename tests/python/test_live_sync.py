"""LiveScene kept across syncs (the Rendered viewport's view_update, F12 with Persistent Data),
under bpy 4.2, against a fresh LiveScene of the same depsgraph after each change (a probe,
2026-12-05): edits made while a sync fails are read once it succeeds again; a sphere renamed to
a deleted sphere's name keeps its own size."""

import warnings
from contextlib import contextmanager

import blender_checks  # noqa: F401  (import path for the shared checks)
import bpy  # noqa: E402  (after harness)
import harness  # before bpy
import numpy as np
import pytest

from bvhlab.blender import ExportError, LiveScene  # noqa: E402
from bvhlab.blender.sphere import SPHERE_PROPERTY  # noqa: E402


@contextmanager
def synced(instancing: bool, monkeypatch):
    """A LiveScene synced from every depsgraph update, as RenderEngine.view_update syncs it; yields
    it, the errors its syncs raised and the walks they made (a list, one entry a walk)."""
    from bvhlab.blender import live as live_module

    live = LiveScene("visible", require_camera=False, allow_empty=True, instancing=instancing)
    errors, walks = [], []
    real = live_module.walk

    def counted(*args, **kwargs):
        walks.append(1)
        return real(*args, **kwargs)

    monkeypatch.setattr(live_module, "walk", counted)

    def view_update(scene, depsgraph):
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                live.sync(depsgraph, scene, depsgraph.view_layer)
        except ExportError as error:
            errors.append(str(error))

    bpy.app.handlers.depsgraph_update_post.append(view_update)
    try:
        yield live, errors, walks
    finally:
        bpy.app.handlers.depsgraph_update_post.remove(view_update)


@pytest.fixture()
def viewport(monkeypatch):
    """synced's LiveScene and errors, in a scene of a camera alone."""
    harness.empty_scene()
    harness.add_camera((0, -15, 0), (0, 0, 0))
    with synced(True, monkeypatch) as (live, errors, _):
        yield live, errors


def fresh_scene(instancing: bool = True):
    live = LiveScene("visible", require_camera=False, allow_empty=True, instancing=instancing)
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


def _sorted_triangles(scene) -> np.ndarray:
    """The scene's world triangles in one order (a live scene's movers are instances of their own,
    a fresh scene's in mesh 0)."""
    t = scene.flattened().triangles.reshape(-1, 9)
    return t[np.lexsort(t.T[::-1])]


def test_a_walk_that_finds_the_same_items_keeps_the_index_of_the_objects_an_update_moves(viewport, monkeypatch):
    """The index of the objects an update moves alone (placed_only.MoverIndex) is made from the
    items' keys and layout: a walked sync (here after a material edit) that finds the same keeps
    it, one that finds another object makes it again (a scene walked at every frame made it anew at
    each: 14-60 ms at 10,000 items); and the moves after it are still placed right."""
    from bvhlab.blender import live as live_module

    made = []
    real = live_module.MoverIndex.of.__func__

    def counted(cls, items, mesh_of):
        made.append(len(items))
        return real(cls, items, mesh_of)

    monkeypatch.setattr(live_module.MoverIndex, "of", classmethod(counted))
    live, errors = viewport
    a, _ = harness.add_box("A", (-2, 0, 0)), harness.add_box("B", (2, 0, 0))
    material = bpy.data.materials.new("M")
    a.data.materials.append(material)
    bpy.context.view_layer.update()
    a.location.z = 1.0  # moved: a walk gives it an instance of its own (another layout)
    bpy.context.view_layer.update()
    a.location.z = 1.5  # moved alone: the index of that layout made
    bpy.context.view_layer.update()
    before = len(made)
    for step in range(3):  # walks that find the same items, each followed by a move placed alone
        material.diffuse_color = (0, 1, step / 3, 1)
        bpy.context.view_layer.update()
        a.location.z = 2.0 + step
        bpy.context.view_layer.update()
    assert len(made) == before, made
    np.testing.assert_allclose(_sorted_triangles(live.scene), _sorted_triangles(fresh_scene()))
    harness.add_box("C", (6, 0, 0))  # another item: made again at the next move
    bpy.context.view_layer.update()
    a.location.z = 6.0
    bpy.context.view_layer.update()
    assert len(made) == before + 1, made
    np.testing.assert_allclose(_sorted_triangles(live.scene), _sorted_triangles(fresh_scene()))
    assert not errors
