"""The sidebar's tree follows the scene (issue 34): animation playback, scrubbing and objects moved or
edited in the viewport update the tree Build made, so its boxes (and stats) follow, in any shading
mode. Blender's depsgraph_update_post and frame_change_post handlers sync a LiveScene of the
tree's scope (only what the depsgraph reports as changed is read again) and update the tree as the
render engine does (trees.SceneTree.update): moving an instance makes a new TLAS only, a moved or
edited mesh has its tree updated with the scene's update policy. Only while the boxes are shown
and no build is running: with them hidden an edit marks the tree behind (state.BuiltTree.behind,
said in the panel), as an undo or redo marks every tree, and the next update with the boxes shown
reads the whole scene again and brings the tree up to date.

Where the work runs: the sync reads bpy data, so it runs on the UI thread, in the handler. A new
TLAS alone (only instances moved: `SyncReport.placeable`) is made there too: it is bounded by the
instance count (binned SAH over instance boxes: 0.4 ms for 100 instances, about 15 ms for 10,000
on the loaded 2-core machine, bench/addon_instancing.py `move_instance_ms`), and the tests and
scripts see the boxes moved at once. Anything that builds or updates a mesh's tree (a deforming or
edited mesh: a rebuild of a big mesh takes seconds) runs on a worker thread that is given only the
exported bvhlab.Scene (no bpy data), the way Build runs its build (background.BackgroundTask): the
overlay keeps drawing the last complete tree until the update is done (SceneTree.update swaps its
tree at the end; a tree updated in place keeps the versions readers hold), later changes made
meanwhile are taken in one update after it (the newest scene; refittable only if every sync in
between was), an error is said in the panel and never raised, and a UI timer redraws the
viewports when it is done."""

from __future__ import annotations

import threading
import warnings
from dataclasses import dataclass
from typing import TYPE_CHECKING

import bpy
from bpy.app.handlers import persistent

from . import state

if TYPE_CHECKING:
    from bvhlab.blender import LiveScene

_live: dict[tuple, LiveScene] = {}  # (scene key, scope) → the LiveScene kept between updates
_failed: set[tuple] = set()  # the (scene key, scope)s whose last catch-up failed to export
_edited_while_building: set[int] = set()  # scene keys changed while their Build ran
#: (scene key, view layer name, scope) → the objects that scope covered at the last export or walk
#: (_shown_objects)
_shown: dict[tuple, frozenset] = {}
_busy = [False]  # a handler does not run inside itself (the sync may evaluate the depsgraph)
#: How often (s) the UI timer looks for a finished worker update to redraw.
REDRAW_POLL_S = 0.05


@dataclass
class _Job:
    """A tree update for the worker: what it needs, none of it bpy data."""

    key: int  # the scene's state.key
    built: object  # the state.BuiltTree whose tree is updated
    scene: object  # the exported bvhlab.Scene
    refittable: bool
    policy: object  # bvhlab.UpdateConfig


class _Worker:
    """One thread at a time updates trees for the handlers; a job given while it runs waits as the
    one pending job of its scene (a newer one replaces it, refittable only if both were)."""

    def __init__(self):
        self._lock = threading.Lock()
        self._pending: dict[int, _Job] = {}
        self._thread: threading.Thread | None = None
        self._current: int | None = None  # the scene key being updated
        self.running = False  # an update is in progress or pending

    def give(self, job: _Job) -> None:
        with self._lock:
            waiting = self._pending.get(job.key)
            if waiting is not None and waiting.built is job.built:
                job.refittable = job.refittable and waiting.refittable
            self._pending[job.key] = job
            self.running = True
            if self._thread is None or not self._thread.is_alive():
                self._thread = threading.Thread(target=self._run, name="bvhlab follow", daemon=True)
                self._thread.start()

    def busy_with(self, key: int) -> bool:
        with self._lock:
            return self.running and (key in self._pending or self._current == key)

    def _run(self) -> None:
        while True:
            with self._lock:
                if not self._pending:
                    self.running, self._current = False, None
                    return
                key, job = self._pending.popitem()
                self._current = key
            _update(job)

    def forget(self, wait_s: float = 10.0) -> None:
        """Drop the pending jobs and wait (up to `wait_s`) for the one running."""
        with self._lock:
            self._pending.clear()
            thread = self._thread
        if thread is not None:
            thread.join(wait_s)

    def wait(self, timeout: float = 60.0) -> bool:
        """Until every job given is done (tests, scripts); True when they are."""
        thread = self._thread
        if thread is not None:
            thread.join(timeout)
        return not self.running


_worker = _Worker()

#: The panel's warning while the tree does not follow; a sync that succeeds takes it away.
_NOT_FOLLOWED = "The boxes no longer follow the scene"


def _update(job: _Job):
    """Update the job's tree (any thread; no bpy). Never raises: an error is said in the panel."""
    from .background import UI_WORK_THREADS

    if state.trees.get(job.key) is not job.built or job.key in state.builds:
        return None  # a Build replaced the tree (or is running): this scene is not its any more
    try:
        update = job.built.tree.update(job.scene, job.refittable, threads=UI_WORK_THREADS, policy=job.policy)
    except Exception as error:  # said in the panel, never raised into Blender
        state.messages[job.key] = ("WARNING", f"{_NOT_FOLLOWED}: {error}")
        job.built.behind = job.built.behind or state.NOT_FOLLOWED
        return None
    return update


def follow(scene, depsgraph):
    """Bring the scene's shown tree up to date with the evaluated depsgraph; returns the
    trees.TreeUpdate of a new TLAS made here, or None (nothing to follow, nothing changed, or the
    update was given to the worker: `wait()` waits for it)."""
    from bvhlab.blender import EmptySceneWarning, ExportError, LiveScene, SubstituteWarning

    from .trees import update_config

    if depsgraph.mode != "VIEWPORT":
        # a render's (F12, an animation's frames, by any engine): it holds what renders show (not
        # objects disabled in renders, but objects hidden by the eye), not what the sidebar's
        # tree is of; followed, it made the tree the render's until the next edit. Nothing is
        # touched: the viewport's evaluations are its own, and this may be the render's thread
        return None
    key = state.key(scene)
    built = state.tree_for(scene)
    if _busy[0] or (built is None and key not in state.builds):
        _missed(key)
        return None
    if key in state.builds or not scene.bvhlab.overlay_show:  # not followed: the tree falls behind
        _missed(key)
        # (a tree behind already is read again whole at its catch-up: no set to keep)
        if _moved_or_edited(depsgraph) or (
            built is not None and not built.behind and _shown_changed(key, depsgraph, built.key.scope)
        ):
            _fell_behind(key, built, building=key in state.builds)
        return None
    live_key = (key, built.key.scope)
    if built.behind:  # catch up: the whole scene read again (the LiveScene kept may be older)
        if live_key in _failed and not _moved_or_edited(depsgraph):
            return None  # the last catch-up failed: again after an edit, not at every click
        _live.pop(live_key, None)
    elif not _moved_or_edited(depsgraph):
        shown_changed = _shown_changed(key, depsgraph, built.key.scope)
        if shown_changed is False:  # a selection, a setting: the tree's objects are the same
            return None
        _missed(key)  # the next sync walks: the updates do not name what changed
        if shown_changed is None:  # a material, a flag: followed at the next move or edit
            return None
        # an object hidden by the eye, a collection excluded (or an object selected in scope
        # "selected"): followed now
    live = _live.get(live_key)
    if live is None:
        # a scene emptied (its last object deleted or hidden) is followed to an empty tree: an
        # error here kept the deleted objects' boxes drawn, and Pick Box picked them
        live = _live[live_key] = LiveScene(built.key.scope, require_camera=False, allow_empty=True)
    _busy[0] = True
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", EmptySceneWarning)  # the empty tree says it
            warnings.simplefilter("ignore", SubstituteWarning)  # a tree needs no camera or light (as Build)
            report = live.sync(depsgraph, scene, depsgraph.view_layer)
    except (ExportError, ValueError) as error:  # said in the panel, never raised into Blender
        state.messages[key] = ("WARNING", f"{_NOT_FOLLOWED}: {error}")
        _failed.add(live_key)
        # the tree is the scene's no longer: Export Stats builds again (it wrote the old tree's
        # stats), the panel says so (a helper's probe)
        built.behind = built.behind or state.NOT_FOLLOWED
        return None
    finally:
        _busy[0] = False
    built.behind = ""
    _failed.discard(live_key)
    if state.messages.get(key, ("", ""))[1].startswith(_NOT_FOLLOWED):  # the panel kept it (an audit)
        del state.messages[key]
    if not report.placed_only:  # walked: objects may have come or gone
        _shown[key, depsgraph.view_layer.name, built.key.scope] = _shown_objects(depsgraph.view_layer, built.key.scope)
    if not report.geometry and not report.full:
        return None
    job = _Job(key, built, live.scene, report.refittable, update_config(scene))
    if report.placeable and not _worker.busy_with(key):  # a TLAS only: bounded (module docstring)
        update = _update(job)
        if update is not None and update.action != "kept":
            _tag_redraw()
        return update
    _worker.give(job)
    _watch_worker()
    return None


def _fell_behind(key: int, built, building: bool) -> None:
    """The scene changed where the tree does not follow it: the scenes kept for following it are
    dropped (an edited mesh whose evaluated data kept its address would be taken as unchanged), and
    the tree is marked (one a Build is making now, when it is done: tree_made)."""
    for live_key in [k for k in _live if k[0] == key]:
        del _live[live_key]
    if building:
        _edited_while_building.add(key)
    elif built is not None and not built.behind:
        built.behind = state.EDITED


def export_taken(key: int, view_layer, scope: str) -> None:
    """A Build has read the scene (ops_build) in `scope`: changes from now on are made while it runs."""
    _edited_while_building.discard(key)
    _shown[key, view_layer.name, scope] = _shown_objects(view_layer, scope)


def tree_made(key: int, built) -> None:
    """A new tree is the sidebar's (operator_support.remember_tree): behind if the scene changed
    while its Build ran (after the Build read it: export_taken)."""
    if key in _edited_while_building:
        _edited_while_building.discard(key)
        built.behind = state.EDITED


def settle(key: int, timeout: float = 120.0) -> bool:
    """Wait (up to `timeout`) for the update the worker is making or will make of scene `key`'s
    tree: an operator reading the tree reads it then (Export Stats wrote the stats of the tree
    before a deletion the worker was taking in: 720,036 primitives for 540,036; a helper's
    probe). True when none is left."""
    import time

    deadline = time.monotonic() + timeout
    while _worker.busy_with(key):
        if time.monotonic() > deadline:
            return False
        time.sleep(0.01)
    return True


def wait(timeout: float = 60.0) -> bool:
    """Wait for the updates given to the worker (tests and scripts); True when all are done."""
    return _worker.wait(timeout)


def _tag_redraw() -> None:
    from .overlay import tag_redraw

    tag_redraw()


_timer: list = [None]  # the redraw timer's function while it is registered


def _watch_worker() -> None:
    """A UI timer (one at a time) that redraws the viewports once the worker's updates are done."""
    if _timer[0] is not None and bpy.app.timers.is_registered(_timer[0]):
        return

    def tick():
        if _worker.running:
            return REDRAW_POLL_S
        _timer[0] = None
        _tag_redraw()
        return None

    _timer[0] = tick
    bpy.app.timers.register(tick, first_interval=REDRAW_POLL_S)


def _missed(key) -> None:
    """An evaluation of scene `key` not synced: its LiveScenes walk at their next sync (one
    placed from the next updates alone would keep an object hidden by the eye meanwhile)."""
    for (scene_key, _scope), live in _live.items():
        if scene_key == key:
            live.missed()


def _shown_objects(view_layer, scope: str) -> frozenset:
    """The objects whose items a tree of `scope` holds, as the view layer says now: the visible
    ones, or the selected ones (bpy structs hash by their address: 18 ms at 20,000 objects, where a
    walk over them takes about a second)."""
    objects = view_layer.objects
    if scope == "selected":
        return frozenset(o for o in objects if o.select_get(view_layer=view_layer))
    return frozenset(o for o in objects if o.visible_get(view_layer=view_layer))


def _shown_changed(key: int, depsgraph, scope: str) -> bool | None:
    """For an evaluation that moved and edited nothing (_moved_or_edited), whether it changed which
    objects `scope` covers: True where it did (an object hidden by the eye or a layer collection's
    eye, both reported as the scene alone; a collection excluded, reported as the scene and its
    objects' shading; a selection in scope "selected"); False where it did not and named the scene
    alone (a selection, the active object, a scene setting: nothing to follow); None where it did
    not and named something else (a material, a holdout or ray-visibility flag: followed at the
    next move or edit, which walks), or named nothing, or no set was recorded since the tree was
    made. Records the set (per view layer and scope: two windows on two view layers of one scene
    would swap it back and forth)."""
    updates = list(depsgraph.updates)
    view_layer = depsgraph.view_layer
    shown = _shown_objects(view_layer, scope)
    before = _shown.get((key, view_layer.name, scope))
    _shown[key, view_layer.name, scope] = shown
    if before is None or not updates:
        return None
    if shown != before:
        return True
    return False if all(isinstance(update.id, bpy.types.Scene) for update in updates) else None


def _moved_or_edited(depsgraph) -> bool:
    """The depsgraph's last evaluation moved an object or changed its geometry (an edited mesh
    reports its objects too), or changed what a collection holds: an object added, deleted, or
    disabled in viewports reports its collections' geometry (a deleted object reports nothing of
    its own). A changed setting of the scene (the overlay's, say) does not count; nor, unseen
    here, an object hidden by the eye or a collection excluded (view-layer state the depsgraph
    reports as the scene alone, or with its objects' shading: _shown_changed)."""
    for update in depsgraph.updates:
        if isinstance(update.id, bpy.types.Object) and (update.is_updated_transform or update.is_updated_geometry):
            return True
        if isinstance(update.id, bpy.types.Collection) and update.is_updated_geometry:
            return True
    return False


@persistent
def _on_update(scene, depsgraph=None) -> None:
    if depsgraph is None:  # Blender before 4.0 passed the scene only
        depsgraph = bpy.context.evaluated_depsgraph_get()
    follow(scene, depsgraph)


def _handlers():
    """(Blender's handler list, this module's handler) pairs."""
    handlers = bpy.app.handlers
    return [
        (handlers.depsgraph_update_post, _on_update),
        (handlers.frame_change_post, _on_update),
        (handlers.undo_post, _after_undo),
        (handlers.redo_post, _after_undo),
    ]


def register() -> None:
    for handlers, handler in _handlers():
        if handler not in handlers:
            handlers.append(handler)


def unregister() -> None:
    for handlers, handler in _handlers():
        if handler in handlers:
            handlers.remove(handler)
    forget()


@persistent
def _after_undo(*_args) -> None:
    """An undo or redo can change any object: every tree may be behind its scene (the next update
    with the boxes shown reads the scene again), and the scenes kept for following are dropped."""
    for built in state.trees.values():
        built.behind = state.UNDONE
    _live.clear()
    _failed.clear()
    _shown.clear()  # the objects are made again: their addresses are new


def forget() -> None:
    """Drop the scenes kept and the updates not started; wait for the one running (its tree is one
    the cache may forget: nothing of bpy is touched)."""
    _worker.forget()
    _live.clear()
    _failed.clear()
    _edited_while_building.clear()
    _shown.clear()
    if _timer[0] is not None and bpy.app.timers.is_registered(_timer[0]):
        bpy.app.timers.unregister(_timer[0])
    _timer[0] = None
