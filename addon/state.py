"""What the add-on remembers between operator calls, in module memory and never in bpy data:
the built tree per scene, the last comparison table, the last message. Keyed by the scene's
session_uid; cleared when a file is loaded and on unregister."""

from __future__ import annotations

import itertools
import time
from dataclasses import dataclass, field

_serials = itertools.count(1)


@dataclass
class BuiltTree:
    """A tree and what it was built from."""

    bvh: object  # bvhlab.Bvh
    scene: object  # the exported bvhlab.Scene
    settings: dict  # BVHLAB_PG_settings.build_settings() at build time
    built_at: float = field(default_factory=time.time)
    serial: int = field(default_factory=lambda: next(_serials))  # changes whenever the tree does

    @property
    def height(self) -> int:
        return self.bvh.stats["height"]


trees: dict[int, BuiltTree] = {}
comparisons: dict[int, list[dict]] = {}
last_render: dict[int, dict] = {}
messages: dict[int, tuple[str, str]] = {}  # (level, text) of the last report
#: The build running for a scene (a background.BackgroundTask, or the operator itself for a build
#: run at once from a script): one at a time, the last one started is the one whose tree is kept.
builds: dict[int, object] = {}


def key(scene) -> int:
    return scene.session_uid


def tree_for(scene) -> BuiltTree | None:
    return trees.get(key(scene))


def clear() -> None:
    for table in (trees, comparisons, last_render, messages, builds):
        table.clear()
