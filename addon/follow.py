"""The sidebar's tree follows the scene (issue 34): animation playback, scrubbing and objects moved or
edited in the viewport update the tree Build made, so its boxes (and stats) follow, in any shading
mode. Blender's depsgraph_update_post and frame_change_post handlers sync a LiveScene of the
tree's scope (only what the depsgraph reports as changed is read again) and update the tree as the
render engine does (trees.SceneTree.update): moving an instance makes a new TLAS only, a moved or
edited mesh has its tree updated with the scene's update policy. Only while the boxes are shown
and no build is running; on the UI thread (a topology change rebuilds that mesh's tree there)."""

from __future__ import annotations

import bpy
from bpy.app.handlers import persistent

from . import state

_live: dict[tuple, object] = {}  # (scene key, scope) → the LiveScene kept between updates
_busy = [False]  # a handler does not run inside itself (the sync may evaluate the depsgraph)


def follow(scene, depsgraph):
    """Bring the scene's shown tree up to date with the evaluated depsgraph; returns the
    trees.TreeUpdate (None when there is nothing to follow or nothing changed)."""
    from bvhlab.blender import ExportError, LiveScene

    from .background import UI_WORK_THREADS
    from .trees import update_config

    key = state.key(scene)
    built = state.tree_for(scene)
    if built is None or not scene.bvhlab.overlay_show or key in state.builds or _busy[0]:
        return None
    if not _moved_or_edited(depsgraph):  # a selection, a setting: no walk over the scene's objects
        return None
    live_key = (key, built.key.scope)
    live = _live.get(live_key)
    if live is None:
        live = _live[live_key] = LiveScene(built.key.scope, require_camera=False)
    _busy[0] = True
    try:
        report = live.sync(depsgraph, scene, depsgraph.view_layer)
        if not report.geometry and not report.full:
            return None
        update = built.tree.update(live.scene, report.refittable, threads=UI_WORK_THREADS, policy=update_config(scene))
    except (ExportError, ValueError) as error:  # said in the panel, never raised into Blender
        state.messages[key] = ("WARNING", f"The boxes no longer follow the scene: {error}")
        return None
    finally:
        _busy[0] = False
    built.scene = live.scene
    if update.action != "kept":
        from .overlay import tag_redraw

        tag_redraw()
    return update


def _moved_or_edited(depsgraph) -> bool:
    """The depsgraph's last evaluation moved an object or changed its geometry (an edited mesh
    reports its objects too); a changed setting of the scene (the overlay's, say) does not count."""
    return any(
        isinstance(update.id, bpy.types.Object) and (update.is_updated_transform or update.is_updated_geometry)
        for update in depsgraph.updates
    )


@persistent
def _on_update(scene, depsgraph=None) -> None:
    if depsgraph is None:  # Blender before 4.0 passed the scene only
        depsgraph = bpy.context.evaluated_depsgraph_get()
    follow(scene, depsgraph)


def register() -> None:
    for handlers in (bpy.app.handlers.depsgraph_update_post, bpy.app.handlers.frame_change_post):
        if _on_update not in handlers:
            handlers.append(_on_update)


def unregister() -> None:
    for handlers in (bpy.app.handlers.depsgraph_update_post, bpy.app.handlers.frame_change_post):
        if _on_update in handlers:
            handlers.remove(_on_update)
    forget()


def forget() -> None:
    _live.clear()
