"""What the engine remembers outside its instances, in module memory (never in bpy data), keyed by
the scene's session_uid: the final renders' trees (Blender makes a new engine per render unless
Persistent Data is on, and a tree over unchanged geometry is worth keeping), and what the last
final render and the viewports did (the panels show it; tests read it). Cleared when a file loads."""

from __future__ import annotations

import threading

final_trees: dict = {}  # scene key → scene_tree.SceneTree
last_final: dict = {}  # scene key → dict: sync totals, tree action, timings, device, ...
last_viewport: dict = {}  # scene key → dict: the latest frame's level, size, timings, device, ...
lock = threading.Lock()  # final renders run on Blender's render thread


def key(blender_scene) -> int:
    return blender_scene.session_uid


def clear() -> None:
    with lock:
        for table in (final_trees, last_final, last_viewport):
            table.clear()
