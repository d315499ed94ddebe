"""Evaluations that only moved instances or changed their own meshes (placed without the walk).

A sync walks every object and instance the depsgraph shows (`walk.py`): about 40 µs an
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
An object that is an instance of its own only for its animation (not seen moving) walks where the
animation is gone (removing a constraint names only a transform). Anything else, or no update at
all, and the walk runs (`placing_from_updates` returns None).

Analytic spheres: a sphere stays in mesh 0 (a scene mesh holds triangles only), so a moved sphere
never becomes an instance; where it is a plain item (as above) and was placed with an extent, its
move is placed too: its centre and radius made again from its new matrix (`place_spheres`), its
row of mesh 0's spheres replaced and every other array kept (mesh 0's tree is then refitted and the
TLAS made again). Moving one sphere beside 100,000 geometry-nodes instances walked them all,
1.3-1.9 s a move (helper probe, 2026-12-07). A sphere scaled to nothing, or from nothing, walks.

Reshaped objects: an edit of one object's mesh in Edit Mode names the object and its mesh with
their geometry; a modifier's setting or `mesh.update()` names both with geometry and shading too;
playback of an armature-deformed or shape-keyed object names the armature (geometry, shading),
the object and its mesh (geometry) and the shape keys (geometry, shading). The walk makes an object
whose mesh it read again and found changed a mover (an instance of its own, as a move does), so
from the second edit on such an object is one item, and its mesh its own; there the sync reads
that one object's mesh again (`place_reshaped`) and keeps every other item, where:
- the object is a plain item (above), the only item of its scene mesh, and has no geometry-nodes
  modifier or particle system (whose new instances only the walk finds);
- on a frame change, its own animation animates nothing but its transform (a keyframed
  visibility is named as geometry);
- every mesh named is the data of such an object and has no other user, every set of shape keys
  named belongs to such a mesh;
- the object is still no sphere, its mesh has triangles, and its slots give the same material
  table indices as before (which checks a shading flag: a holdout or a ray visibility changed
  walks);
- an armature is named in no item's key (an armature object is never exported: its pose reaches
  the meshes it deforms, which Blender names, and the children of its bones, named as moved).

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

from .instancing import Item, Layout, SharedMesh, invertible
from .material_table import MaterialTable, look_of, map_slots
from .mesh import read_mesh
from .motion import animates_more_than_transform, animates_only_transform, transform_animated
from .scope import matrices_array
from .sphere import is_analytic_sphere, place_sphere
from .sync_report import SyncReport

#: Object types whose transform moves no item by itself (see the module's docstring).
PASSIVE_TYPES = frozenset({"CAMERA", "LIGHT"})
#: Object types never exported whose every update reaches the exported items only through updates
#: of their own (an armature: the objects it deforms, the children of its bones).
DEFORMER_TYPES = frozenset({"ARMATURE"})


@dataclass
class MoverIndex:
    """The items of a sync that an update of their object's transform places alone: `plain` maps an
    original object's full name to (its item's key, its row in the sync's matrices); `named` holds
    every name in an item's key (owners and shown objects); `alone` the keys of the plain items
    that are the only instance of their scene mesh (whose geometry an update may read alone).
    Plain items are instances of a scene mesh or analytic spheres of mesh 0 (the module's
    docstring)."""

    plain: dict[str, tuple[tuple, int]]
    named: frozenset[str]
    alone: frozenset[tuple] = frozenset()

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
            for row, (key, item) in enumerate(items.items())
            if not key[2]
            and key[0] == key[1]
            and uses[key[0]] == 1
            and (mesh_of[key] or (item.mesh is None and item.slot_table is not None))
        }
        members = Counter(mesh_of.values())
        alone = frozenset(key for key, _ in plain.values() if mesh_of[key] and members[mesh_of[key]] == 1)
        return cls(plain, frozenset(uses), alone)

    @staticmethod
    def still_holds(old_items: dict, old_layout: Layout | None, items: dict, layout: Layout) -> bool:
        """Whether the index `of` the last sync's items and layout is that of a walked sync's too:
        the same keys in the same order, the same instances, and the same items spheres with
        primitives (a scene walked at every frame, e.g. an animated scatter, made it anew at each:
        14-60 ms at 10,000 items, helper probe; a sphere made a mesh again kept its place as a
        sphere, and its next move left mesh 0's triangles where they were: the review)."""
        return (
            old_layout is not None
            and list(items) == list(old_items)
            and layout.mesh_of == old_layout.mesh_of
            and [_placed_as(i) for i in items.values()] == [_placed_as(i) for i in old_items.values()]
        )


def _placed_as(item: Item) -> tuple[bool, bool]:
    """What of an item MoverIndex.of reads beside its key and mesh: sphere, and primitives."""
    return item.mesh is None, item.slot_table is not None


@dataclass
class Placing:
    """What an evaluation changed where the walk can be skipped (placing_from_updates): `moved` maps
    an item's key to (its row, its world matrix as a mathutils.Matrix copy); `reshaped` an item's
    key to (its row, its evaluated object, whose mesh is to be read again); `spheres` (place_spheres)
    a moved sphere's row in mesh 0's spheres to its new (cx, cy, cz, radius)."""

    moved: dict[tuple, tuple]
    reshaped: dict[tuple, tuple]
    spheres: dict[int, np.ndarray] = dataclasses.field(default_factory=dict)

    def rows(self) -> np.ndarray:
        """The rows of the items moved or reshaped (a row may be given twice)."""
        rows = [row for row, _ in self.moved.values()] + [row for row, _ in self.reshaped.values()]
        return np.array(rows, np.int64)


def placing_from_updates(
    depsgraph, index: MoverIndex, frame_changed: bool = False, seen_moving: set | frozenset = frozenset()
) -> Placing | None:
    """The items whose objects' updates are all the evaluation reports, moved or reshaped, or None
    where the walk must run (the module's docstring). `frame_changed`: the scene's frame is not the
    last sync's (see the module's docstring); `seen_moving`: the keys of the items seen moving or
    reshaped so far (LiveScene's)."""
    placing = Placing({}, {})
    meshes = []  # the meshes and shape keys named, judged once every object is known
    reported = False
    for update in depsgraph.updates:
        reported = True
        obj = update.id  # the evaluated ID
        if frame_changed and isinstance(obj, bpy.types.Action):
            continue  # named with the objects it animates, which are judged by their own updates
        if isinstance(obj, (bpy.types.Mesh, bpy.types.Key)):
            meshes.append(obj.original)
            continue
        if not isinstance(obj, bpy.types.Object):
            return None
        original = obj.original
        name = original.name_full
        found = index.plain.get(name)
        if found is not None and update.is_updated_geometry:
            key, row = found
            # its new geometry may hold instances (the walk would find them), and on a frame change
            # its keyframed visibility is named as geometry too
            if key not in index.alone or _instances(original) or _may_instance(original):
                return None
            if frame_changed and animates_more_than_transform(original):
                return None
            placing.reshaped[key] = (row, obj)  # its slots are checked as it is read (a shading flag)
            if update.is_updated_transform:
                placing.moved[key] = (row, obj.matrix_world.copy())
            continue
        if original.type in DEFORMER_TYPES and name not in index.named:
            continue
        if not update.is_updated_transform or update.is_updated_geometry:
            return None
        if update.is_updated_shading and not (frame_changed and animates_only_transform(original)):
            return None
        if found is not None:
            # a transform is all Blender names when an object becomes an instancer or the child of
            # one (Instancing, Parent: new instances the walk would find)
            if _instances(original):
                return None
            key, row = found
            # an instance of its own only for its animation, which is gone (removing a constraint
            # names only a transform): the walk puts it back into mesh 0 where it did not move
            if key in index.alone and key not in seen_moving and not transform_animated(original):
                return None
            placing.moved[key] = (row, obj.matrix_world.copy())
            continue
        kind = original.type
        passive = kind in PASSIVE_TYPES or (kind == "EMPTY" and original.instance_type == "NONE")
        if name in index.named or not passive:
            return None
    if meshes and not _own_meshes(meshes, [obj for _, obj in placing.reshaped.values()]):
        return None
    return placing if reported else None


def _instances(original) -> bool:
    """Whether an object instances, or its parent does."""
    parent = original.parent
    return original.instance_type != "NONE" or (parent is not None and parent.instance_type != "NONE")


def _may_instance(original) -> bool:
    """Whether an object's evaluated geometry may hold instances: it has a geometry-nodes modifier
    or a particle system (an edit of its settings names its geometry alone, and neither
    `instance_type` nor `is_instancer` says so under bpy 4.2)."""
    return bool(original.particle_systems) or any(m.type == "NODES" for m in original.modifiers)


def _own_meshes(named: list, reshaped) -> bool:
    """Whether each mesh in `named` (originals) is the data of a reshaped object and of nothing
    else, and each set of shape keys the keys of such a mesh."""
    own = {obj.original.data.name_full for obj in reshaped if obj.original.data is not None}
    for data in named:
        mesh = data.user if isinstance(data, bpy.types.Key) else data
        if mesh is None or mesh.name_full not in own or mesh.users != 1:
            return False
    return True


def place_moved(
    items: dict, world: np.ndarray, moved_before: list, seen_moving: set, moved: dict, instancing: bool
) -> tuple | None:
    """(items, world, report, seen moving, the keys of the items moved) of a sync that found the
    last sync's `items` and `world` (its matrices, row i the i-th item's; `moved_before`: the keys
    of its items that moved) with the matrices of `moved` (placing_from_updates), as the walk
    would find them (walk.py `_compare_matrices`); None where a new matrix cannot be inverted as
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


def place_spheres(placed: tuple, rows: dict[tuple, int], mesh_of: dict) -> dict[int, np.ndarray] | None:
    """The new (cx, cy, cz, radius) of each sphere that moved in a placed sync (`placed`:
    place_moved's tuple, whose items get them as placed), by its row in mesh 0's spheres (`rows`:
    scene_arrays.mesh_zero's, of the last sync that made mesh 0); None where one is scaled to
    nothing now and was not before, or the other way round, or where an item of mesh 0 that moved
    is no sphere (the walk then makes mesh 0 again). Raises ExportError as the walk's export does
    (a centre out of range)."""
    items, now = placed[0], placed[4]
    spheres = {}
    for key in now:
        item: Item = items[key]
        if item.mesh is not None:
            if not mesh_of[key]:  # its triangles are mesh 0's, placed where it was: only the walk places them
                return None
            continue
        assert item.bounds is not None  # a sphere keeps its object-space bounds
        sphere, row = place_sphere(item.bounds, item.matrix, item.name), rows.get(key)
        if (row is None) == bool(sphere.size):
            return None
        item.placed = sphere  # the item is place_moved's copy
        if row is not None:
            spheres[row] = sphere
    return spheres


def place_reshaped(
    placed: tuple,
    layout: Layout,
    shared: list[SharedMesh],
    reshaped: dict,
    table: MaterialTable,
    layer_eval,
    instancing: bool,
) -> list[SharedMesh] | None:
    """The shared meshes of a placed sync (`placed`: place_moved's tuple, whose items, report, seen
    moving and moved keys are updated in place) with each reshaped item's (placing_from_updates)
    mesh read again, as the walk reads it; None where the walk must run after all (the object
    became a sphere, has no triangles now, or its slots give other material indices)."""
    items, _, report, seen_moving, now = placed
    shared = list(shared)
    for key, (_, obj) in reshaped.items():
        item: Item = items[key]
        if is_analytic_sphere(obj):
            return None
        mesh = read_mesh(obj, item.name)
        if not mesh.triangle_count:
            return None
        data = obj.data.as_pointer()
        tables = len(table.materials)
        slots = table.slot_indices(obj, data, look_of(obj, obj, layer_eval))
        if len(table.materials) != tables or item.slot_table is None or not np.array_equal(slots, item.slot_table):
            return None
        shared[layout.mesh_of[key] - 1] = SharedMesh(mesh, mesh.triangles, map_slots(slots, mesh.slots))
        items[key] = dataclasses.replace(item, mesh=mesh, data=data, placed=None, moved=False)
        report.objects_read += 1
        if key in now:  # a new mesh: the walk counts no move of it (walk.py _compare_matrices)
            now.remove(key)
            report.objects_moved -= 1
        if instancing and (item.mesh is None or not mesh.same_as(item.mesh)):  # as the walk counts it
            seen_moving.add(key)
    return shared
