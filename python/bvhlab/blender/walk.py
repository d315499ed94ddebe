"""A LiveScene sync's walk (live.py): every object and instance the depsgraph shows, in its
order, each read again where the updates name its geometry (or it is new) and kept from the last
sync where not; the items' matrices compared with the last sync's (moved, seen moving)."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from .depsgraph_updates import Dirty
from .instancing import Item
from .material_table import Look, MaterialTable, look_of
from .mesh import MeshData, read_mesh
from .scope import instances_in_scope, matrices_array
from .sphere import is_analytic_sphere, sphere_bounds
from .sync_report import SyncReport


class LastSync(NamedTuple):
    """What the walk compares with: the last sync's items (key → Item, in walk order), its meshes by
    data address, its items' world matrices (row i the i-th item's) and the keys of the items seen
    moving or reshaped so far."""

    items: dict
    by_data: dict
    world: np.ndarray
    seen_moving: set


#: Object types that can have primitives. A curve, text, surface or metaball object (mesh.py
#: CONVERTIBLE_TYPES) is shown by the depsgraph as itself (its data a Curve, TextCurve, ...) and as
#: an instance of type MESH holding its evaluated surface (Blender 4.2 to 5.3 alike): Cycles renders
#: the mesh alone (object_is_geometry: the object's data is a Mesh), and so does the export — read
#: through the object too, every such triangle was exported twice.
GEOMETRY_TYPES = frozenset({"MESH"})


def _address(data, addresses: dict) -> int:
    """The address of an evaluated mesh object's mesh data during this evaluation: the same for
    every object and instance that shows that mesh (linked duplicates without modifiers of their
    own, collection, vertex, face and geometry-nodes instances). `addresses` remembers it per mesh
    for the walk (bpy structs hash by their address; as_pointer is a slower method call)."""
    address = addresses.get(data)
    if address is None:
        address = addresses[data] = data.as_pointer()
    return address


def _vertex_count(obj) -> int:
    return len(obj.data.vertices) if obj.type == "MESH" and obj.data is not None else -1


def walk(depsgraph, view_layer, scope: str, dirty: Dirty, table: MaterialTable, last: LastSync, instancing: bool):
    """Every object in scope, read again when dirty or new (a mesh shared by several items
    once), kept when not; in the depsgraph's order (the order export_scene has always used).
    Each item's material table index of each slot is read here: an instance's object is valid
    only while it is the depsgraph iterator's current item (geometry-nodes and nested
    collection instances crashed Blender when their slots were read after the loop had moved
    on). Returns (items, their world matrices (N,4,4) in walk order, meshes by data address,
    the report, the keys of the items seen moving or reshaped so far: movers, `instancing.plan`).

    10,000 instances of one object make one part (shown object, mesh data): whether it is a
    sphere and its slots are asked once per part; per item only what differs (key, matrix)."""
    items: dict[tuple, Item] = {}
    fresh: dict[int, MeshData] = {}  # meshes read in this sync, by data address
    by_data: dict[int, MeshData] = {}
    parts: dict[tuple, tuple] = {}  # (shown object's name, data address, look) → (sphere, slot table)
    looks: dict[tuple, Look] = {}  # (owner, shown object), originals → how it shows its materials
    layer_flags: dict = {}  # owner (evaluated) → (holdout, indirect only) in the view layer
    layer_eval = depsgraph.view_layer_eval  # what the evaluated owners' flags are asked of
    addresses: dict = {}  # evaluated mesh (hashed by its address) → its address: as_pointer once
    report = SyncReport()
    reshaped = []  # the keys of the items seen before whose mesh changed: movers from now on
    differs: dict[tuple, bool] = {}  # (data address, id of the old mesh) → the mesh read differs
    for entry in instances_in_scope(depsgraph, view_layer, scope, GEOMETRY_TYPES):
        obj, key = entry.obj, entry.key
        old = last.items.get(key)
        changed = dirty.everything or dirty.geometry_of(obj, key)
        data = _address(obj.data, addresses)  # every entry is a MESH (GEOMETRY_TYPES)
        look = looks.get((entry.owner, entry.source))
        if look is None:
            look = looks[entry.owner, entry.source] = look_of(entry.holder, obj, layer_eval, layer_flags)
        part = parts.get((key[1], data, look))
        if part is None:
            part = (is_analytic_sphere(obj), None)
        if part[0]:
            # an item of this name before may be another object's sphere (renamed to this name)
            if old is None or old.mesh is not None or old.sphere_data != data or changed:
                bounds = sphere_bounds(obj)
                report.objects_read += 1
            else:
                assert old.bounds is not None  # a sphere keeps its object-space bounds
                bounds = old.bounds
            slots = table.slot_indices(obj, look=look)
            item = Item(None, bounds, entry.matrix, None, slots, key, sphere_data=data)
        else:
            mesh = fresh.get(data)
            if mesh is None:
                mesh = None if changed else _known_mesh(last, old, data, obj)
                if mesh is None:
                    mesh = fresh[data] = read_mesh(obj, entry.name)
                    report.objects_read += 1
            by_data[data] = mesh
            if changed and old is not None and old.mesh is not None:
                # compared once per mesh, not per item: 10,000 duplicates of an edited mesh share both
                pair = (data, id(old.mesh))
                if pair not in differs:
                    differs[pair] = not mesh.same_as(old.mesh)
                if differs[pair]:
                    reshaped.append(key)
            slots = part[1]
            if slots is None and mesh.triangle_count:
                slots = table.slot_indices(obj, data, look)
                parts[(key[1], data, look)] = (False, slots)
            item = Item(mesh, None, entry.matrix, data, slots, key)
        item.origin = (key[0], entry.owner, key[1], entry.source)
        items[key] = item
    # each item's Matrix copy (a key seen twice keeps its last, as the dict does), all at once
    world = matrices_array([item.matrix for item in items.values()])
    seen_moving = _compare_matrices(last, items, world, report, instancing)
    if instancing:
        seen_moving.update(reshaped)
    for item in items.values():  # a clean item seen before a changed one of the same mesh
        if item.data is not None and item.data in fresh and item.mesh is not fresh[item.data]:
            item.mesh, item.placed, item.moved = fresh[item.data], None, False
    return items, world, by_data, report, seen_moving


def _compare_matrices(last: LastSync, items: dict, world: np.ndarray, report: SyncReport, instancing: bool) -> set:
    """Give each item its row of `world`; an item seen last sync with the same mesh keeps its
    placed primitives if its matrix is the same, else is `moved`. Returns the keys of the items
    seen moving so far (this sync's and before, of the items still there)."""
    seen_moving = last.seen_moving & items.keys()
    previous = {key: row for row, key in enumerate(last.items)}
    rows = np.fromiter((previous.get(key, -1) for key in items), np.int64, len(items))
    same = np.ones(len(items), bool)  # new items count as unmoved
    known = np.flatnonzero(rows >= 0)
    same[known] = (last.world[rows[known]] == world[known]).all(axis=(1, 2))  # NaN: moved
    olds = last.items
    for (key, item), matrix, row, unmoved in zip(items.items(), world, rows, same):
        item.matrix = matrix
        if row < 0:
            continue
        if not unmoved and instancing:
            seen_moving.add(key)
        old = olds[key]
        if old.mesh is item.mesh and old.bounds is item.bounds:
            if unmoved:
                item.placed = old.placed
            else:
                item.moved = True
                report.objects_moved += 1
    return seen_moving


def _known_mesh(last: LastSync, old: Item | None, data: int, obj) -> MeshData | None:
    """The mesh read before for an item whose geometry did not change, or None to read it."""
    if old is not None and old.mesh is not None and old.data == data:
        return old.mesh
    mesh = last.by_data.get(data)
    if mesh is not None and len(mesh.positions) == _vertex_count(obj):
        return mesh
    return None
