"""Evaluations that only moved instances (LiveScene's placing without the walk).

A sync walks every object and instance the depsgraph shows (`LiveScene._walk`): about 40 µs an
item under bpy 4.2, so moving one object of 20,000 linked duplicates took 0.84-1.05 s a sync, a
frame a second while an object is dragged in the Rendered viewport. Where all that
`depsgraph.updates` reports is that some objects moved, and each of them is an instance of the
scene already (its own mesh and transform: an animated or once-moved object, a linked duplicate),
the sync can take each one's new matrix from its update and keep everything else, as the walk
would have found it.

What counts (measured under bpy 4.2; Blender names the same updates from 4.2 to 5.3): moving an
object reports that object alone (`is_updated_transform`); moving a parent reports it and each
child; moving an object inside an instanced collection also reports the collection and the
instancer; hiding an object by the eye reports only the scene, and so does linking one; a
visibility or holdout flag reports shading. So the walk is skipped only where every update is a
transform, and no more, of:
- an object that is one item of the last sync, as itself (key (name, name, ())), an instance of
  the scene (`Layout.mesh_of` nonzero), and named in no other item's key (not an instancer, not
  shown by instances), that instances nothing and whose parent instances nothing (setting
  Instancing or Parent names only a transform, though the walk would find new instances);
- a camera or a light (a sync gathers both anyway);
- an empty that instances nothing and is in no item's key (a parent, reported with its children).
Anything else, or no update at all, and the walk runs (`moved_items` returns None).

A frame change (playback, scrubbing) names each animated object with its transform and shading,
and each action that animates them (shading). There, an object's shading is let through where its
animation data animates its transform alone (`motion.animates_only_transform`: its action's, NLA
strips' and drivers' paths all transform paths), and the actions are passed over; keyframed
visibility, ray visibility, materials or data still walk (named without a transform, or as data).
"""

from __future__ import annotations

import dataclasses
from collections import Counter
from dataclasses import dataclass

import bpy
import numpy as np

from .instancing import invertible
from .motion import animates_only_transform
from .scope import matrices_array
from .sync_report import SyncReport

#: Object types whose transform moves no item by itself (see the module's docstring).
PASSIVE_TYPES = frozenset({"CAMERA", "LIGHT"})


@dataclass
class MoverIndex:
    """The items of a sync that an update of their object's transform places alone: `plain` maps an
    original object's full name to (its item's key, its row in the sync's matrices); `named` holds
    every name in an item's key (owners and shown objects)."""

    plain: dict[str, tuple[tuple, int]]
    named: frozenset[str]

    @classmethod
    def of(cls, items: dict, mesh_of: dict) -> MoverIndex:
        """Of a sync's items (key → Item, in walk order) and its layout's `mesh_of`."""
        uses: Counter = Counter()
        for owner, shown, _ in items:
            uses[owner] += 1
            if shown != owner:
                uses[shown] += 1
        plain = {
            key[0]: (key, row)
            for row, key in enumerate(items)
            if not key[2] and key[0] == key[1] and uses[key[0]] == 1 and mesh_of[key]
        }
        return cls(plain, frozenset(uses))


def moved_items(depsgraph, index: MoverIndex, frame_changed: bool = False) -> dict[tuple, tuple] | None:
    """{key: (row, world matrix as a mathutils.Matrix copy)} of the items whose objects' updates
    are all the evaluation reports, or None where the walk must run (the module's docstring).
    `frame_changed`: the scene's frame is not the last sync's (see the module's docstring)."""
    moved: dict[tuple, tuple] = {}
    reported = False
    for update in depsgraph.updates:
        reported = True
        obj = update.id  # the evaluated ID
        if frame_changed and isinstance(obj, bpy.types.Action):
            continue  # named with the objects it animates, which are judged by their own updates
        if not isinstance(obj, bpy.types.Object):
            return None
        if not update.is_updated_transform or update.is_updated_geometry:
            return None
        original = obj.original
        if update.is_updated_shading and not (frame_changed and animates_only_transform(original)):
            return None
        name = original.name_full
        found = index.plain.get(name)
        if found is not None:
            # a transform is all Blender names when an object becomes an instancer or the child of
            # one (Instancing, Parent: new instances the walk would find)
            parent = original.parent
            if original.instance_type != "NONE" or (parent is not None and parent.instance_type != "NONE"):
                return None
            key, row = found
            moved[key] = (row, obj.matrix_world.copy())
            continue
        kind = original.type
        passive = kind in PASSIVE_TYPES or (kind == "EMPTY" and original.instance_type == "NONE")
        if name in index.named or not passive:
            return None
    return moved if reported else None


def place_moved(
    items: dict, world: np.ndarray, moved_before: list, seen_moving: set, moved: dict, instancing: bool
) -> tuple | None:
    """(items, world, report, seen moving, the keys of the items moved) of a sync that found the
    last sync's `items` and `world` (its matrices, row i the i-th item's; `moved_before`: the keys
    of its items that moved) with the matrices of `moved` (moved_items), as the walk would find
    them (live.py `_compare_matrices`); None where a new matrix cannot be inverted as
    `instancing.plan` asks of an instance (the walk then places that item in mesh 0)."""
    before, world = world, world.copy()
    rows = np.fromiter((row for row, _ in moved.values()), np.int64, len(moved))
    if len(rows):
        world[rows] = matrices_array([matrix for _, matrix in moved.values()])
        if not invertible(world[rows, :3, :3]).all():
            return None
    # the items, none of them moved (those that moved last sync keep their new place), then those
    # whose matrix changed (NaN: changed, as the walk counts it)
    items = dict(items)
    for key in moved_before:
        items[key] = dataclasses.replace(items[key], moved=False)
    changed = ~(before[rows] == world[rows]).all(axis=(1, 2))
    report = SyncReport(placed_only=True)
    seen_moving = set(seen_moving)
    now = []
    for (key, (row, _)), differs in zip(moved.items(), changed):
        if not differs:
            continue
        items[key] = dataclasses.replace(items[key], matrix=world[row], placed=None, moved=True)
        now.append(key)
        if instancing:
            seen_moving.add(key)
    report.objects_moved = len(now)
    return items, world, report, seen_moving, now
