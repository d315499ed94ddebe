"""Moving an analytic sphere is placed without the walk (placed_only.place_spheres), under bpy 4.2:
a sphere stays in mesh 0, so its move walked every object and instance of the scene (1.3-1.9 s a
move beside 100,000 geometry-nodes instances, helper probe 2026-12-07). Each sync's spheres
against a fresh LiveScene of the same depsgraph, bit for bit; the walks counted; a sphere scaled to
nothing and back walks (its row comes or goes). The add-on's boxes follow such a move by a refit
of mesh 0 and a new TLAS, and hit what a fresh export's tree hits."""

from importlib import import_module

import blender_checks  # noqa: F401  (import path for the shared checks)
import bpy  # noqa: E402  (after harness)
import harness  # before bpy
import numpy as np
import pytest
from test_live_sync import _sorted_triangles, fresh_scene, synced  # noqa: E402
from test_moving_objects import _same_hits  # noqa: E402

from bvhlab.blender import export_scene  # noqa: E402
from bvhlab.blender.sphere import SPHERE_PROPERTY  # noqa: E402


def _sphere(name, location, radius):
    bpy.ops.mesh.primitive_uv_sphere_add(radius=radius, location=location, segments=12, ring_count=6)
    obj = bpy.context.active_object
    obj.name = name
    obj[SPHERE_PROPERTY] = True
    return obj


def spheres_among_duplicates():
    """Six linked duplicates of one box (instances of a scene mesh), a box used once (mesh 0), a
    cone's worth of triangles, and three spheres in mesh 0: A, B and C (C scaled to nothing)."""
    harness.empty_scene()
    harness.add_camera((0, -15, 4), (0, 0, 0))
    shared = harness.add_box("Shared", (-4, 0, 0))
    for i in range(5):
        dup = bpy.data.objects.new(f"Dup {i}", shared.data)
        bpy.context.scene.collection.objects.link(dup)
        dup.location = (-4 + 1.5 * i, 3, 0)
    harness.add_box("Floor", (0, 0, -2), scale=(8, 8, 0.2))
    _sphere("A", (-1, 0, 1), 0.5)
    _sphere("B", (2, 0, 1), 1.5)
    _sphere("C", (4, 2, 1), 1.0).scale = (0, 0, 0)
    bpy.context.view_layer.update()


@pytest.mark.parametrize("instancing", [True, False], ids=["instanced", "flat"])
def test_a_moved_sphere_is_placed_without_the_walk_and_equals_a_fresh_export(instancing, monkeypatch):
    spheres_among_duplicates()
    with synced(instancing, monkeypatch) as (live, errors, walks):
        bpy.data.objects["Floor"].location.x += 0.5  # the first sync walks
        bpy.context.view_layer.update()
        assert live.scene is not None and live.scene.is_instanced == instancing
        assert len(live.scene.spheres) == 2

        def step(change, walked: int):
            before = len(walks)
            change()
            bpy.context.view_layer.update()
            assert not errors, errors
            assert len(walks) - before == walked, (change.__name__, walks)
            want = fresh_scene(instancing)
            np.testing.assert_array_equal(live.scene.spheres, want.spheres)
            np.testing.assert_array_equal(live.scene.sphere_material, want.sphere_material)
            if instancing:
                np.testing.assert_array_equal(live.scene.instance_transforms, want.instance_transforms)
            np.testing.assert_array_equal(live.scene.triangles, want.triangles)

        a, b, c = (bpy.data.objects[n] for n in "ABC")

        def move_b():
            b.location = (2.5, -1.0, 1.25)

        def turn_and_grow_a():
            a.rotation_euler = (0.3, 0.2, 1.1)
            a.scale = (1.7, 1.7, 1.7)

        def b_to_nothing():
            b.scale = (0, 0, 0)

        def b_back():
            b.scale = (1, 1, 1)

        def c_back():
            c.scale = (0.5, 0.5, 0.5)

        def move_both():
            a.location.z += 1.0
            c.location.x -= 1.0

        step(move_b, 0)
        step(turn_and_grow_a, 0)
        assert live.scene.spheres[0, 3] == pytest.approx(0.5 * 1.7, rel=1e-3)
        step(b_to_nothing, 1)  # its row goes: the walk makes mesh 0 again
        assert len(live.scene.spheres) == 1
        step(b_back, 1)  # and comes back
        step(c_back, 1)  # C's first extent
        assert len(live.scene.spheres) == 3
        step(move_both, 0)  # two rows at once, C's after A's and B's
        step(move_b, 0)


def test_the_boxes_follow_a_moved_sphere_by_a_refit_and_hit_what_a_fresh_export_hits():
    harness.enable_addon_from_source()
    spheres_among_duplicates()
    assert bpy.ops.bvhlab.build() == {"FINISHED"} and bpy.context.scene.bvhlab.overlay_show
    follow = import_module(f"{harness.addon().__name__}.follow")
    built = harness.addon().state.tree_for(bpy.context.scene)
    for x in (1.0, 0.0, -2.0):
        bpy.data.objects["B"].location.x = x
        bpy.context.view_layer.update()
        assert follow.wait()
        assert built.tree.last.action in ("refit", "built"), built.tree.last
        _same_hits(built.bvh, export_scene(bpy.context, require_camera=False))
    assert built.tree.last.action == "refit", built.tree.last  # from the second move on: placed


@pytest.mark.parametrize("instancing", [True, False], ids=["instanced", "flat"])
def test_a_sphere_made_a_mesh_again_moves_as_a_mesh(instancing, monkeypatch):
    """The index of what an update places kept the item as a sphere of mesh 0 when its flag came off
    (the walk found the same keys and layout), and its next move left mesh 0's triangles where they
    were (the review)."""
    spheres_among_duplicates()
    with synced(instancing, monkeypatch) as (live, errors, _):
        a = bpy.data.objects["A"]
        for change in (
            lambda: setattr(a.location, "x", a.location.x + 1.0),  # placed as a sphere
            lambda: (a.pop(SPHERE_PROPERTY), a.data.update()),  # a mesh again (the flag alone names nothing)
            lambda: setattr(a.location, "x", a.location.x + 3.0),
            lambda: setattr(a.location, "z", a.location.z - 1.0),
            lambda: (a.__setitem__(SPHERE_PROPERTY, True), a.data.update()),  # a sphere again
            lambda: setattr(a.location, "y", a.location.y + 2.0),
        ):
            change()
            bpy.context.view_layer.update()
            assert not errors, errors
            want = fresh_scene(instancing)
            np.testing.assert_array_equal(live.scene.spheres, want.spheres)
            np.testing.assert_allclose(_sorted_triangles(live.scene), _sorted_triangles(want), atol=1e-5)
