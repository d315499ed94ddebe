"""What the add-on remembers, in module memory and never in bpy data, keyed by the scene's
session_uid: the tree the sidebar shows (from the one cache of trees, trees.py), the last
comparison table, render and message, the builds running, and what the render engine's last final
render and viewports did (the panels show it; the tests read it). Cleared when a file is loaded
and on unregister. The one state module of the add-on: its operators, panels and render engine
all read and write here."""

from __future__ import annotations

import threading
import time
from dataclasses import dataclass, field

from .trees import SceneTree, TreeKey


@dataclass
class BuiltTree:
    """The tree the sidebar shows: the one Build (or Render, or Export) made last, in the cache.
    Its Bvh is the cache's: a refit by the viewport or F12 shows here too."""

    key: TreeKey
    tree: SceneTree
    built_at: float = field(default_factory=time.time)
    #: Why the scene may differ from the tree now ("" while it fits, as far as the add-on knows):
    #: EDITED, objects moved or edited while the boxes were hidden (the tree follows the scene only
    #: while they are shown: follow.py); UNDONE, an undo or redo, which can change anything;
    #: RENDERED, a final render made the shared tree fit what renders show (rendered_over);
    #: NOT_FOLLOWED, the follow failed to read or update the scene (follow.py). The
    #: panel says it; showing the boxes brings the tree up to date, as Build and Export stats do.
    behind: str = ""

    @property
    def bvh(self):
        return self.tree.bvh

    @property
    def scene(self):
        """The exported bvhlab.Scene the tree was last made to fit: the cache's (trees.SceneTree
        .scene), so a Rendered viewport that updates the shared tree updates it too."""
        return self.tree.scene

    @property
    def settings(self) -> dict:
        """What the tree was built with: the scope and the build settings (BuildConfig's)."""
        return {"scope": self.key.scope, **self.key.config.tree_settings()}

    @property
    def height(self) -> int:
        """The depths the overlay's range spans: the tree's height, or for a two-level tree the
        larger of its TLAS's and its deepest BLAS's (the range applies within each level)."""
        stats = self.bvh.stats
        if "tlas_height" in stats:
            return max(stats["tlas_height"], max(stats["mesh_height"], default=0))
        return stats["height"]

    @property
    def serial(self) -> tuple:
        """Changes whenever the tree does (a build, a refit): what the overlay's batch depends on."""
        return (id(self.tree), self.tree.generation)


#: BuiltTree.behind's reasons
EDITED, UNDONE, RENDERED, NOT_FOLLOWED = "edited", "undone", "rendered", "not followed"

trees: dict[int, BuiltTree] = {}
comparisons: dict[int, list[dict]] = {}
last_render: dict[int, dict] = {}
messages: dict[int, tuple[str, str]] = {}  # (level, text) of the last report
#: What the panel says above all else when the core loaded is not this zip's (core_check.py), or "".
core_warning = ""
#: The build running for a scene (a background.BackgroundTask, or the operator itself for a build
#: run at once from a script): one at a time, the last one started is the one whose tree is kept.
builds: dict[int, object] = {}
#: The render engine: the last final render (sync totals, tree action, timings, device, ...) and
#: the latest frame of each viewport level; written from Blender's render thread and the
#: viewport's worker, hence the lock.
last_final: dict[int, dict] = {}
last_viewport: dict[int, dict] = {}
lock = threading.Lock()
#: The box picked in the viewport (ops_inspect.py): (the tree's serial when picked, node, how). A
#: pick of an older tree (rebuilt or refit since) is not shown.
picked: dict[int, tuple] = {}
#: The sidebar's Traversal Counters (ops_counters.py): "histogram" (Render Counter's
#: bvhlab.histogram.CounterHistogram) and "difference" (Compare Two Trees' summary).
counter_results: dict[int, dict] = {}


def remember_pick(scene, built: BuiltTree, node: int, how: str) -> None:
    """Pick `node` of the scene's current tree (ops_inspect.py: a click, a step, a button)."""
    picked[key(scene)] = (built.serial, node, how)


def picked_node(scene) -> int | None:
    """The node picked on the scene's current tree, or None."""
    built, pick = tree_for(scene), picked.get(key(scene))
    return pick[1] if built is not None and pick is not None and pick[0] == built.serial else None


def rendered_over(tree: SceneTree) -> None:
    """A final render (F12, an animation's frame) changed `tree` to fit what renders show (objects
    disabled in renders left out, ones hidden by the eye in): the one cache's trees are shared, so
    a sidebar that shows this tree is behind its scene (RENDERED) until it catches up (the next
    update with the boxes shown, Build, Export stats). Any thread (the render's): one assignment."""
    for built in list(trees.values()):
        if built.tree is tree and not built.behind:
            built.behind = RENDERED


def key(scene) -> int:
    return scene.session_uid


def tree_for(scene) -> BuiltTree | None:
    built = trees.get(key(scene))
    return built if built is not None and built.bvh is not None else None


def clear() -> None:
    from .trees import cache

    with lock:
        tables = (trees, comparisons, last_render, messages, builds, last_final, last_viewport, picked)
        for table in (*tables, counter_results):
            table.clear()
    cache.clear()
