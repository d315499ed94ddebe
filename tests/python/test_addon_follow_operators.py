"""Operators that read the sidebar's tree while the follow (issue 34) updates it or after it
failed, under bpy 4.2 (a helper's probe of the add-on's operators): Export Stats and Fresh SAH read
the tree the worker is making, a follow that fails leaves the tree behind (Export Stats wrote the
old tree's figures), Fresh SAH of an emptied scene, and output paths refused before any work."""

import threading
from importlib import import_module

import blender_checks  # noqa: F401  (import path for the shared checks)
import bpy  # noqa: E402  (after harness)
import harness  # before bpy
import pytest
from blender_instance_scenes import suzanne  # noqa: E402
from test_addon_follow import HeldUpdate, built_monkey  # noqa: E402


@pytest.fixture(scope="module", autouse=True)
def addon_enabled():
    harness.enable_addon_from_source()


def _addon(name: str):
    return import_module(f"{harness.addon().__name__}.{name}")


def _stats_file(path):
    import json

    return json.loads(path.read_text())["stats"]


def test_export_stats_reads_the_tree_the_follow_is_making(tmp_path, monkeypatch):
    """The mesh swapped for a smaller one while the worker's update is held: Export Stats waits
    for it and writes the new tree's primitives (it wrote the old tree's: 720,036 for 540,036). The
    update is released when the UI thread first asks whether it is running (what waiting for it
    does): an export that does not wait reads the held tree's old stats, however slow the machine."""
    built, monkey = built_monkey()
    state, follow = harness.addon().state, _addon("follow")
    tree = built.tree
    before = built.bvh.stats["primitives"]
    held = tree.update = HeldUpdate(tree)
    busy_with = follow._worker.busy_with

    def asked(key):
        if threading.current_thread() is threading.main_thread():
            held.release.set()
        return busy_with(key)

    try:
        monkey.data = suzanne("Smaller", subdivisions=1).data
        bpy.context.view_layer.update()  # the handler gives the rebuild to the worker, held
        assert len(held.threads) == 1 and not held.release.is_set()
        monkeypatch.setattr(follow._worker, "busy_with", asked)
        path = tmp_path / "stats.json"
        assert bpy.ops.bvhlab.export_stats(filepath=str(path)) == {"FINISHED"}
    finally:
        held.release.set()
        follow.wait()
        del tree.update
    written = _stats_file(path)["primitives"]
    assert written < before and written == state.tree_for(bpy.context.scene).bvh.stats["primitives"], (written, before)


def test_a_follow_that_fails_leaves_the_tree_behind_and_export_stats_says_why(tmp_path):
    """A NaN vertex while the boxes follow: the follow says it fails, the tree is behind (the panel
    says so), and Export Stats builds again, which refuses the scene, rather than write the old
    tree's stats."""
    built, monkey = built_monkey()
    state = harness.addon().state
    monkey.data.vertices[0].co.x = float("nan")
    monkey.data.update()
    bpy.context.view_layer.update()
    assert "no longer follow" in state.messages[state.key(bpy.context.scene)][1]
    assert state.tree_for(bpy.context.scene).behind == state.NOT_FOLLOWED
    path = tmp_path / "stats.json"
    with pytest.raises(RuntimeError, match="not a finite number"):
        bpy.ops.bvhlab.export_stats(filepath=str(path))
    assert not path.exists()
    monkey.data.vertices[0].co.x = 0.0  # an edit: followed again
    monkey.data.update()
    bpy.context.view_layer.update()
    _addon("follow").wait()
    assert not state.tree_for(bpy.context.scene).behind


def test_fresh_sah_of_an_emptied_scene():
    """Every object deleted while the boxes follow: an empty tree, whose fresh build costs 0 too
    (ZeroDivisionError before)."""
    built_monkey()
    for obj in [o for o in bpy.context.scene.objects if o.type == "MESH"]:
        bpy.data.objects.remove(obj)
    bpy.context.view_layer.update()
    _addon("follow").wait()
    state = harness.addon().state
    assert state.tree_for(bpy.context.scene).bvh.stats["primitives"] == 0
    assert bpy.ops.bvhlab.fresh_sah() == {"FINISHED"}
    assert "a fresh build's 0.00" in state.messages[state.key(bpy.context.scene)][1]


def test_output_paths_are_refused_before_any_work(tmp_path):
    """Export Stats to ".json" (written as ".json.json" and ".json.csv"); Compare to a folder or
    another suffix (said after measuring every method)."""
    built_monkey()
    state = harness.addon().state
    with pytest.raises(RuntimeError, match="no stem"):
        bpy.ops.bvhlab.export_stats(filepath=str(tmp_path / ".json"))
    assert not list(tmp_path.iterdir())
    settings = bpy.context.scene.bvhlab
    settings.backend, settings.compare_frames = "cpu", 1
    for target, message in ((tmp_path, "is a folder"), (tmp_path / "table.txt", "written as .csv")):
        settings.compare_filepath = str(target)
        with pytest.raises(RuntimeError, match=message):
            bpy.ops.bvhlab.compare()
        assert state.key(bpy.context.scene) not in state.comparisons
    assert not list(tmp_path.iterdir())
    settings.compare_filepath = str(tmp_path / "table")  # no suffix: .csv added, as Export Stats adds .json
    assert bpy.ops.bvhlab.compare() == {"FINISHED"}
    assert [p.name for p in tmp_path.iterdir()] == ["table.csv"]
