"""The sidebar's tree follows an edited mesh off the UI thread (issue 34), under bpy 4.2: the
depsgraph handler syncs the scene and gives the tree update (a refit or a rebuild of the mesh's
tree) to a worker thread; the overlay keeps the last complete tree meanwhile, edits made while it
runs are taken in one later update, an error on the worker is said in the panel and never raised,
and the tree then hits what a fresh build over a fresh export hits."""

import threading
from importlib import import_module

import blender_checks  # noqa: F401  (import path for the shared checks)
import bpy  # noqa: E402  (after harness)
import harness  # before bpy
import numpy as np
import pytest
from blender_instance_scenes import suzanne  # noqa: E402
from test_moving_objects import _same_hits  # noqa: E402

from bvhlab.blender import export_scene  # noqa: E402


@pytest.fixture(scope="module", autouse=True)
def addon_enabled():
    harness.enable_addon_from_source()


def _addon(name: str):
    return import_module(f"{harness.addon().__name__}.{name}")


def built_monkey():
    """A 15,744-triangle Suzanne and a floor, built with the boxes shown."""
    harness.empty_scene()
    harness.add_camera((0.5, -12.0, 5.0), (0.0, 0.5, 0.0), lens=30)
    harness.add_point_light((3.0, -5.0, 6.0))
    harness.add_box("Floor", (0.0, 0.0, -1.5), size=1.0, scale=(6.0, 6.0, 0.2))
    monkey = suzanne("Edited", subdivisions=2)
    bpy.context.scene.collection.objects.link(monkey)
    bpy.context.view_layer.update()
    assert bpy.ops.bvhlab.build() == {"FINISHED"} and bpy.context.scene.bvhlab.overlay_show
    return harness.addon().state.tree_for(bpy.context.scene), monkey


def _edit(monkey, dz: float) -> None:
    mesh = monkey.data
    for k in range(0, len(mesh.vertices), 9):
        mesh.vertices[k].co.z += dz
    mesh.update()
    bpy.context.view_layer.update()  # depsgraph_update_post: the handler


class HeldUpdate:
    """Stands in for the SceneTree's update: records the thread and call, waits for `release`."""

    def __init__(self, tree, fail: bool = False):
        self.tree, self.update, self.fail = tree, tree.update, fail
        self.release, self.entered, self.threads = threading.Event(), threading.Event(), []

    def __call__(self, *args, **kwargs):
        self.threads.append(threading.current_thread())
        self.entered.set()
        assert self.release.wait(60), "never released"
        if self.fail:
            raise RuntimeError("the update failed on purpose")
        return self.update(*args, **kwargs)


def test_an_edited_mesh_is_followed_on_a_worker_keeping_the_last_tree_drawn():
    built, monkey = built_monkey()
    state, follow = harness.addon().state, _addon("follow")
    tree, before = built.tree, built.bvh
    generation = tree.generation
    held = tree.update = HeldUpdate(tree)
    try:
        _edit(monkey, 0.3)  # returns although the update is held: it is not on this thread
        # the worker is in the update before the next edits (a fast edit could come before it
        # starts and join the first: a helper's audit)
        assert held.entered.wait(60), "the update never started"
        _edit(monkey, 0.2)  # and again while it runs: pending
        _edit(monkey, -0.1)  # replaces the pending one
        assert len(held.threads) == 1 and held.threads[0] is not threading.main_thread()
        assert state.tree_for(bpy.context.scene).bvh is before and tree.generation == generation
        held.release.set()
        assert follow.wait()
    finally:
        del tree.update
    assert len(held.threads) == 2, "the edits made meanwhile were not taken in one update"
    assert tree.generation > generation and tree.last.action in ("refit", "built"), tree.last
    _same_hits(state.tree_for(bpy.context.scene).bvh, export_scene(bpy.context, require_camera=False))


def test_an_error_on_the_worker_is_said_and_the_tree_kept():
    built, monkey = built_monkey()
    state, follow = harness.addon().state, _addon("follow")
    tree, before = built.tree, built.bvh
    held = tree.update = HeldUpdate(tree, fail=True)
    held.release.set()
    try:
        _edit(monkey, 0.3)
        assert follow.wait()
    finally:
        del tree.update
    level, message = state.messages[state.key(bpy.context.scene)]
    assert level == "WARNING" and "failed on purpose" in message
    assert state.tree_for(bpy.context.scene).bvh is before
    assert np.isfinite(before.stats["sah_cost"])


def test_a_tree_left_behind_is_said_and_caught_up_when_the_boxes_show(tmp_path):
    """With the boxes hidden the tree does not follow: an edit marks it behind (the panel says so),
    and showing the boxes reads the scene again and updates the tree; an undo marks it behind too
    (the probe's case: a tree over a sphere undone away kept 972 primitives for a 12-triangle
    scene), and Export stats then writes the stats of the scene as it is."""
    built, monkey = built_monkey()
    state, follow, panels = harness.addon().state, _addon("follow"), _addon("panels")
    scene = bpy.context.scene
    settings = scene.bvhlab
    triangles = built.bvh.stats["primitives"]
    settings.overlay_show = False
    bpy.context.view_layer.update()
    assert not state.tree_for(scene).behind  # a setting is not an edit
    _edit(monkey, 0.3)
    assert state.tree_for(scene).behind == state.EDITED and "edited" in panels.BEHIND_NOTES[state.EDITED]
    generation = built.tree.generation
    settings.overlay_show = True
    bpy.context.view_layer.update()  # the handler catches up
    assert follow.wait()
    assert not state.tree_for(scene).behind and built.tree.generation > generation
    _same_hits(state.tree_for(scene).bvh, export_scene(bpy.context, require_camera=False))

    settings.overlay_show = False
    bpy.ops.ed.undo_push(message="before the box")
    harness.add_box("Added", (3.0, 0.0, 0.0))
    bpy.context.view_layer.update()
    bpy.ops.ed.undo_push(message="the box")
    assert bpy.ops.bvhlab.build() == {"FINISHED"} and settings.overlay_show  # Build shows the boxes
    bpy.ops.ed.undo_push(message="built")
    assert state.tree_for(scene).bvh.stats["primitives"] == triangles + 12
    bpy.ops.ed.undo()
    bpy.ops.ed.undo()  # the box is gone, the boxes hidden as they were
    scene = bpy.context.scene
    assert "Added" not in scene.objects and not scene.bvhlab.overlay_show
    assert state.tree_for(scene).behind == state.UNDONE
    assert state.tree_for(scene).bvh.stats["primitives"] == triangles + 12  # as built
    assert bpy.ops.bvhlab.export_stats(filepath=str(tmp_path / "behind.json")) == {"FINISHED"}
    assert not state.tree_for(scene).behind
    assert state.tree_for(scene).bvh.stats["primitives"] == triangles


def test_a_deleted_or_disabled_object_is_followed():
    """An object deleted, or disabled in viewports, reports no change of its own to the depsgraph,
    only its collection's: the boxes follow it (they kept the deleted object's boxes), and with the
    boxes hidden the tree is marked behind."""
    built, monkey = built_monkey()
    state, follow = harness.addon().state, _addon("follow")
    scene = bpy.context.scene
    triangles = built.bvh.stats["primitives"]
    floor = bpy.data.objects["Floor"]
    floor.hide_viewport = True
    bpy.context.view_layer.update()
    assert follow.wait() and state.tree_for(scene).bvh.stats["primitives"] == triangles - 12
    floor.hide_viewport = False
    bpy.context.view_layer.update()
    assert follow.wait() and state.tree_for(scene).bvh.stats["primitives"] == triangles
    bpy.data.objects.remove(floor)
    bpy.context.view_layer.update()
    assert follow.wait() and state.tree_for(scene).bvh.stats["primitives"] == triangles - 12
    scene.bvhlab.overlay_show = False
    bpy.context.view_layer.update()
    bpy.data.objects.remove(monkey)
    bpy.context.view_layer.update()
    assert state.tree_for(scene).behind == state.EDITED


def test_a_tree_made_or_caught_up_elsewhere_is_followed_from_the_scene_as_it_is():
    """An edit the tree does not follow drops the scene kept for following it (a mesh edited then,
    whose evaluated data kept its address, would later be taken as unchanged); an edit made while a
    Build runs marks the tree that Build makes (it read the scene before), and a Build that reads
    the scene after the edit does not."""
    built, monkey = built_monkey()
    state, follow, support = harness.addon().state, _addon("follow"), _addon("operator_support")
    scene = bpy.context.scene
    key = state.key(scene)
    _edit(monkey, 0.2)  # followed: a LiveScene is kept
    assert follow.wait() and any(k[0] == key for k in follow._live)
    scene.bvhlab.overlay_show = False
    _edit(monkey, 0.3)
    assert state.tree_for(scene).behind == state.EDITED and not any(k[0] == key for k in follow._live)

    state.builds[key] = "a Build running"  # as the modal Build's task holds it
    try:
        _edit(monkey, -0.2)
    finally:
        del state.builds[key]
    made = support.remember_tree(bpy.context, built.key)  # what the Build's end does
    assert made.behind == state.EDITED
    assert bpy.ops.bvhlab.build() == {"FINISHED"} and not state.tree_for(scene).behind
    _same_hits(state.tree_for(scene).bvh, export_scene(bpy.context, require_camera=False))


def test_a_catch_up_that_fails_is_tried_again_after_an_edit_not_at_every_update(monkeypatch):
    """A scene that cannot be exported (a NaN vertex) fails the catch-up once, says so, and is read
    again only after an edit: not at a selection or a setting; the catch-up that succeeds takes the
    panel's warning away (it was kept: an audit)."""
    from bvhlab.blender import LiveScene

    built, monkey = built_monkey()
    state = harness.addon().state
    scene = bpy.context.scene
    scene.bvhlab.overlay_show = False
    bpy.context.view_layer.update()
    monkey.data.vertices[0].co.x = float("nan")
    monkey.data.update()
    bpy.context.view_layer.update()
    assert state.tree_for(scene).behind == state.EDITED
    syncs = []
    sync = LiveScene.sync
    monkeypatch.setattr(LiveScene, "sync", lambda self, *a, **k: syncs.append(1) or sync(self, *a, **k))
    scene.bvhlab.overlay_show = True
    bpy.context.view_layer.update()
    assert len(syncs) == 1 and "no longer follow" in state.messages[state.key(scene)][1]
    bpy.data.objects["Floor"].select_set(True)
    scene.bvhlab.overlay_depth_max = 3
    bpy.context.view_layer.update()
    assert len(syncs) == 1  # not read again
    monkey.data.vertices[0].co.x = 0.0
    monkey.data.update()
    bpy.context.view_layer.update()
    assert len(syncs) == 2 and not state.tree_for(scene).behind
    assert "no longer follow" not in state.messages.get(state.key(scene), ("", ""))[1]  # said no more


def test_an_object_hidden_while_the_boxes_follow_is_gone_at_once_and_after_the_next_move():
    """Hiding an object by the eye reports only the scene, as a selection does: the follow tells
    them apart by the objects the tree's scope covers, and follows the hide at once (its boxes were
    kept until the next edit, with nothing said: helper probe); the next move, whose updates name
    that move alone, keeps it hidden."""
    built, monkey = built_monkey()
    state, follow = harness.addon().state, _addon("follow")
    scene = bpy.context.scene
    first = bpy.data.objects["Floor"]
    duplicates = []
    for i in range(4):  # instances of the floor's mesh
        obj = bpy.data.objects.new(f"Tile{i}", first.data)
        scene.collection.objects.link(obj)
        obj.location = (-4.5 + 3 * i, 4.0, -1.5)
        duplicates.append(obj)
    bpy.context.view_layer.update()
    assert follow.wait()
    duplicates[0].location.z += 0.5  # followed, placed from its update
    bpy.context.view_layer.update()
    assert follow.wait() and state.tree_for(scene).tree.last.action == "placed"
    primitives = state.tree_for(scene).bvh.stats["primitives_flattened"]
    duplicates[1].hide_set(True)
    bpy.context.view_layer.update()
    assert follow.wait() and state.tree_for(scene).bvh.stats["primitives_flattened"] == primitives - 12
    duplicates[2].location.z += 0.5
    bpy.context.view_layer.update()
    assert follow.wait()
    tree = state.tree_for(scene)
    assert tree.bvh.stats["primitives_flattened"] == primitives - 12
    _same_hits(tree.bvh, export_scene(bpy.context, require_camera=False))


def test_a_selection_reads_nothing_and_the_next_move_is_placed_from_its_update(monkeypatch):
    """A click that selects (the scene alone named, the objects in scope the same) walks nothing,
    and the next move is placed from its update: every selection made the next move walk the whole
    scene (100,000 geometry-nodes instances: 2 s a move, helper probe)."""
    from bvhlab.blender import LiveScene

    built, monkey = built_monkey()
    state, follow = harness.addon().state, _addon("follow")
    scene = bpy.context.scene
    tiles = []
    for i in range(3):  # instances of the floor's mesh: a move of one is placed from its update
        obj = bpy.data.objects.new(f"Tile{i}", bpy.data.objects["Floor"].data)
        scene.collection.objects.link(obj)
        obj.location = (-4.5 + 3 * i, 4.0, -1.5)
        tiles.append(obj)
    bpy.context.view_layer.update()
    assert follow.wait()
    tiles[0].location.z += 0.5
    bpy.context.view_layer.update()
    assert follow.wait() and state.tree_for(scene).tree.last.action == "placed"
    reports = []
    sync = LiveScene.sync
    monkeypatch.setattr(LiveScene, "sync", lambda self, *a, **k: reports.append(sync(self, *a, **k)) or reports[-1])
    tiles[2].select_set(True)
    bpy.context.view_layer.objects.active = tiles[1]
    bpy.context.view_layer.update()
    assert reports == []
    tiles[0].location.z += 0.5
    bpy.context.view_layer.update()
    assert follow.wait()
    assert [r.placed_only for r in reports] == [True]
    assert state.tree_for(scene).tree.last.action == "placed"
    _same_hits(state.tree_for(scene).bvh, export_scene(bpy.context, require_camera=False))


def test_an_object_hidden_with_the_boxes_hidden_leaves_the_tree_behind():
    """With the boxes hidden nothing is followed: an object hidden by the eye then marks the tree
    behind (said in the panel; Export Stats exports again), as an edit does; a selection does not."""
    built, monkey = built_monkey()
    state = harness.addon().state
    scene = bpy.context.scene
    scene.bvhlab.overlay_show = False
    bpy.context.view_layer.update()
    bpy.data.objects["Floor"].select_set(True)
    bpy.context.view_layer.update()
    assert not state.tree_for(scene).behind
    bpy.data.objects["Floor"].hide_set(True)
    bpy.context.view_layer.update()
    assert state.tree_for(scene).behind == state.EDITED


def test_a_collection_excluded_while_the_boxes_follow_is_gone_at_once():
    """Excluding a collection reports the scene and its objects' shading, no move or edit: the
    objects the tree's scope covers differ, so it is followed at once (review)."""
    built, monkey = built_monkey()
    state, follow = harness.addon().state, _addon("follow")
    scene = bpy.context.scene
    crates = bpy.data.collections.new("Crates")
    scene.collection.children.link(crates)
    crate = bpy.data.objects.new("Crate", bpy.data.objects["Floor"].data.copy())
    crates.objects.link(crate)
    bpy.context.view_layer.update()
    assert follow.wait()
    primitives = state.tree_for(scene).bvh.stats["primitives"]  # one flat tree: every mesh used once
    bpy.context.view_layer.layer_collection.children["Crates"].exclude = True
    bpy.context.view_layer.update()
    assert follow.wait()
    assert state.tree_for(scene).bvh.stats["primitives"] == primitives - 12
    _same_hits(state.tree_for(scene).bvh, export_scene(bpy.context, require_camera=False))


def test_a_scene_emptied_while_the_boxes_follow_has_an_empty_tree_and_is_followed_again():
    """Deleting the scene's last object left its boxes drawn (and picked) under "the boxes no longer
    follow the scene: no mesh in scope": the tree follows it to empty, and back."""
    harness.empty_scene()
    harness.add_box("Floor", (0.0, 0.0, -1.5), size=1.0, scale=(6.0, 6.0, 0.2))
    bpy.context.view_layer.update()
    assert bpy.ops.bvhlab.build() == {"FINISHED"}
    state, follow = harness.addon().state, _addon("follow")
    scene = bpy.context.scene
    assert state.tree_for(scene).bvh.stats["primitives"] == 12
    bpy.data.objects.remove(bpy.data.objects["Floor"])
    bpy.context.view_layer.update()
    assert follow.wait()
    assert state.tree_for(scene).bvh.stats["primitives"] == 0
    assert "no longer follow" not in (state.messages.get(state.key(scene)) or ("", ""))[1]
    harness.add_box("Floor again", (0.0, 0.0, -1.0), size=1.0, scale=(6.0, 6.0, 0.2))
    bpy.context.view_layer.update()
    assert follow.wait()
    assert state.tree_for(scene).bvh.stats["primitives"] == 12
    _same_hits(state.tree_for(scene).bvh, export_scene(bpy.context, require_camera=False))
