"""Blender's instancing → a `bvhlab.Scene`'s meshes and instances (issue 34).

Objects and instances that show the same evaluated mesh data with the same materials share one
mesh: collection instances (nested ones too), linked duplicates (objects sharing a mesh
data-block, without modifiers of their own), instancing by vertices or faces and geometry-nodes
instances all reach the exporter as depsgraph items whose evaluated `data` is one mesh. The key is
that mesh (its address during the evaluation) and the material table index of each slot, so an
object whose object-level materials differ gets a mesh of its own. A key used by two or more
items becomes a mesh of the scene (stored once, in object space) with one instance per item (its
world matrix); everything else (objects used once, spheres, instances whose matrix cannot be
inverted, such as a zero scale) is placed into the world in mesh 0 as before, which one identity
instance places. Without any shared mesh the scene is the flat scene of before.

Except movers: an item whose transform is animated (motion.py) or that was seen moving is a mesh
and an instance of its own even when used once, so that moving it makes only a new TLAS (mesh 0,
and its tree, stay as they are). Static objects used once stay merged in mesh 0: a static scene
traces one tree as before.

Mirroring instances keep their matrix: the tracers move a hit's normal back by the inverse
transpose, so the outside stays out, as Blender shows it (`MeshData.world_triangles` reverses the
winding of a mirrored object placed in mesh 0 to match)."""

from __future__ import annotations

from dataclasses import dataclass, field
from itertools import islice

import numpy as np

from .. import _core
from ..scene import MAX_COORDINATE
from .errors import ExportError
from .material_table import map_slots
from .mesh import MeshData, check_world_positions
from .scope import item_name

#: A mesh key used this many times or more becomes a shared mesh with instances.
MIN_INSTANCES = 2
#: |det| of an instance's linear part at most this fraction of Hadamard's bound (the product of its
#: columns' lengths) cannot be inverted (core_cpp/src/tlas/transform.cpp, validate_transform,
#: refuses 1e-6; a margin of 10 keeps float32 rounding of the matrix from crossing it): such an
#: instance (a zero scale) goes into mesh 0 as world triangles.
SINGULAR_FRACTION = 1e-5
#: The largest |entry| of an instance's linear part and of its inverse: half the core's
#: MAX_TRANSFORM_ENTRY (2^76, transform.h: beyond it rays cannot follow into the mesh), a margin for
#: the float32 rounding of the matrix; such an instance (scaled by less than ~1e-23) goes into mesh 0.
MAX_ENTRY = _core.MAX_TRANSFORM_ENTRY / 2


@dataclass(slots=True)
class Item:
    """One object or instance as last read: its mesh (None for a sphere), a sphere's object-space
    bounds, the world matrix (4×4 float64, a row of the sync's matrices, see `plan`; during the
    walk the mathutils.Matrix read), the address of its evaluated mesh data during this evaluation
    (None for a sphere), the material table index of each
    slot (None: no primitives), its key (scope.InScope.key, which names it), its world-space
    primitives once placed (kept while neither mesh nor matrix changes), whether only its matrix
    changed, and the original objects it comes from (whose animation makes it a mover)."""

    mesh: MeshData | None
    bounds: np.ndarray | None
    matrix: np.ndarray
    data: int | None
    slot_table: np.ndarray | None
    key: tuple
    placed: np.ndarray | None = None
    moved: bool = False  # the same mesh as last sync, a different matrix
    origin: tuple = ()  # (owner's name, owner, shown object's name, shown object): originals (motion.py)
    sphere_data: int | None = None  # a sphere's mesh data address: its bounds are that data's

    @property
    def name(self) -> str:
        """For messages."""
        return item_name(self.key)

    @property
    def shape(self) -> tuple:
        return ("sphere",) if self.mesh is None else ("mesh", self.mesh.triangle_count)


@dataclass
class Layout:
    """Which items share a mesh: `mesh_of[key]` is the scene mesh (1..) of each instanced item, 0
    for the items placed in mesh 0; `groups` lists each shared mesh's key (data, slot table)."""

    mesh_of: dict = field(default_factory=dict)
    groups: list = field(default_factory=list)
    _rows: tuple | None = field(default=None, repr=False, compare=False)

    def same_as(self, other: Layout | None) -> bool:
        return other is not None and self.mesh_of == other.mesh_of

    def instance_rows(self) -> tuple[np.ndarray, np.ndarray]:
        """(the scene mesh of each item, int32 (N,), 0 for mesh 0; each item's position among the
        instances in walk order, int64 (N,), -1 for mesh 0's), made once per layout."""
        if self._rows is None:
            every = np.fromiter(self.mesh_of.values(), np.int32, len(self.mesh_of))
            position = np.cumsum(every != 0) - 1
            position[every == 0] = -1
            self._rows = (every, position)
        return self._rows


def plan(items: dict, matrices: np.ndarray, share: bool, is_mover=None) -> Layout:
    """The layout of `items` (key → Item, in walk order; `matrices` (N,4,4): their world matrices,
    row i the i-th item's): which of them become instances. `is_mover(key)`: whether an item used
    once gets a mesh and an instance of its own anyway (it moves); asked only of the items that
    would otherwise be placed in mesh 0."""
    layout = Layout(mesh_of=dict.fromkeys(items, 0))
    if is_mover is None:
        is_mover = _never
    rows = [
        row
        for row, (key, item) in enumerate(items.items())
        if share
        and item.mesh is not None
        and item.slot_table is not None
        and item.mesh.triangle_count > 0
        and (item.data is not None or is_mover(key))
    ]
    if not rows:
        return layout
    keys, values = list(items), list(items.values())
    members: dict[tuple, list] = {}
    tables: dict[int, bytes] = {}  # id of a slot table (shared by the items of one part) → its bytes
    for row in np.flatnonzero(invertible(matrices[rows, :3, :3])):
        key, item = keys[rows[row]], values[rows[row]]
        table = item.slot_table
        assert table is not None  # a candidate
        slots = tables.get(id(table))
        if slots is None:
            slots = tables[id(table)] = table.tobytes()
        data = item.data if item.data is not None else ("item", key)  # no mesh data known: its own
        members.setdefault((data, slots), []).append(key)
    for group, keys in members.items():
        if len(keys) >= MIN_INSTANCES or any(is_mover(key) for key in keys):
            layout.groups.append(group)
            for key in keys:
                layout.mesh_of[key] = len(layout.groups)
    return layout


def _never(key) -> bool:
    return False


def invertible(linear: np.ndarray) -> np.ndarray:
    """bool (N,): which of the (N,3,3) linear parts can be inverted (see SINGULAR_FRACTION) and
    have their entries and their inverse's within MAX_ENTRY. The inverse is the adjugate over the
    determinant, whose rows are the cross products of the columns: its bound is tested as
    max |adjugate| <= MAX_ENTRY · |det|, with no inverse made (100,000 instances: 24 ms, as
    np.linalg.det alone took; with np.linalg.inv 300 ms, at every sync of a moving scene)."""
    m = [[linear[:, r, c] for c in range(3)] for r in range(3)]  # m[r][c]: (N,) each
    with np.errstate(invalid="ignore", over="ignore"):
        columns = [m[0][c] * m[0][c] + m[1][c] * m[1][c] + m[2][c] * m[2][c] for c in range(3)]
        bound = np.sqrt(columns[0] * columns[1] * columns[2])  # Hadamard's: the columns' lengths
        # adjugate[r][c] = the cofactor of m[c][r]: row r is the cross product of columns r + 1, r + 2
        adjugate = [
            [
                m[(c + 1) % 3][(r + 1) % 3] * m[(c + 2) % 3][(r + 2) % 3]
                - m[(c + 1) % 3][(r + 2) % 3] * m[(c + 2) % 3][(r + 1) % 3]
                for c in range(3)
            ]
            for r in range(3)
        ]
        det = m[0][0] * adjugate[0][0] + m[1][0] * adjugate[0][1] + m[2][0] * adjugate[0][2]
        largest = np.abs(linear).max(axis=(1, 2))
        largest_adjugate = np.max(np.abs(np.stack([a for row in adjugate for a in row])), axis=0)
        return (
            np.isfinite(det)
            & (np.abs(det) > SINGULAR_FRACTION * bound)
            & (largest <= MAX_ENTRY)
            & (largest_adjugate <= MAX_ENTRY * np.abs(det))
        )


@dataclass
class SharedMesh:
    """A mesh of the scene (1..): its object-space triangles and their material indices."""

    mesh: MeshData
    triangles: np.ndarray
    tri_material: np.ndarray


def shared_meshes(items: dict, layout: Layout, previous: list[SharedMesh]) -> list[SharedMesh]:
    """One SharedMesh per group, reusing the arrays of `previous` (the last sync's) where the mesh
    read and the materials are the same, so unchanged meshes keep their arrays (and trees)."""
    first = {}
    for key, k in layout.mesh_of.items():
        if k and k not in first:
            first[k] = items[key]
    # the last sync's by mesh read (a search through all of them for each mesh took 14 s a sync for
    # 10,000 movers, each a mesh of its own)
    by_mesh: dict[int, list[SharedMesh]] = {}
    for p in previous:
        by_mesh.setdefault(id(p.mesh), []).append(p)
    out = []
    for k in range(1, len(layout.groups) + 1):
        item = first[k]
        assert item.mesh is not None and item.slot_table is not None  # plan() shares meshes only
        materials = map_slots(item.slot_table, item.mesh.slots)
        candidates = by_mesh.get(id(item.mesh), ())
        reused = next(
            (p for p in candidates if p.mesh is item.mesh and np.array_equal(p.tri_material, materials)), None
        )
        out.append(reused or SharedMesh(item.mesh, item.mesh.triangles, materials))
    return out


def instance_transforms(
    layout: Layout, matrices: np.ndarray, meshes: list[SharedMesh]
) -> tuple[np.ndarray, np.ndarray]:
    """(mesh index int32 (N,), object-to-world float32 (N,3,4)) of the instanced items, in walk
    order (`matrices`: every item's, as given to `plan`). Raises ExportError naming an instance
    that reaches outside the coordinate range."""
    every = layout.instance_rows()[0]
    rows = np.flatnonzero(every)
    mesh_of, chosen_matrices = every[rows], matrices[rows, :3, :4]
    # every instance at once (a loop over the meshes compared mesh_of with each: 10,000 movers, each
    # a mesh of its own, made 10^8 comparisons and 10,000 calls a sync)
    _check_reach(_mesh_bounds(meshes)[mesh_of - 1], chosen_matrices, lambda i: _row_name(layout, int(rows[i])))
    return mesh_of, chosen_matrices.astype(np.float32)


def _mesh_bounds(meshes: list[SharedMesh]) -> np.ndarray:
    """(M, 2, 3) float64: each shared mesh's object-space bounds (lo, hi)."""
    if not meshes:
        return np.zeros((0, 2, 3))
    return np.stack([np.asarray(m.mesh.bounds, np.float64) for m in meshes])


def _row_name(layout: Layout, row: int) -> str:
    return item_name(next(islice(layout.mesh_of, int(row), None)))


def transforms_again(
    transforms: np.ndarray, layout: Layout, matrices: np.ndarray, meshes: list[SharedMesh], rows: np.ndarray
) -> np.ndarray:
    """`transforms`, instance_transforms' float32 (M,3,4) of a sync with the same layout (after
    mesh 0's identity where the scene leads with it), with the instances of the items at `rows`
    made from `matrices` (every item's, as given to `plan`) again: the others kept, not converted
    and checked again (a sync that moved one instance of 20,000). Raises ExportError as
    instance_transforms does for those it makes."""
    every, position = layout.instance_rows()
    rows = np.unique(rows)
    rows = rows[every[rows] != 0]
    out = transforms.copy()
    # the moved instances at once (one call per row cost 60 µs: 0.6 s a frame for 10,000 movers)
    bounds = np.stack([np.asarray(meshes[k - 1].mesh.bounds, np.float64) for k in every[rows]]) if len(rows) else None
    if bounds is not None:
        _check_reach(bounds, matrices[rows, :3, :4], lambda i: _row_name(layout, int(rows[i])))
    out[len(transforms) - int(np.count_nonzero(every)) + position[rows]] = matrices[rows, :3, :4].astype(np.float32)
    return out


#: (8, 3): which of (lo, hi) each corner of a box takes along each axis.
_CORNER_BITS = np.array([[(c >> a) & 1 for a in range(3)] for c in range(8)])


#: Instances whose corners _check_reach places at once (bounds its arrays: 8 corners × 3 float64 each).
_REACH_CHUNK = 1 << 16


def _check_reach(bounds: np.ndarray, matrices: np.ndarray, name_of) -> None:
    """The world corners of each instance's box must be inside the coordinate range; `bounds`:
    (N, 2, 3), each instance's mesh's box; `name_of(i)`: instance i's name, for the message."""
    bounds = np.asarray(bounds, np.float64)
    axes = np.arange(3)
    for start in range(0, len(matrices), _REACH_CHUNK):
        part = matrices[start : start + _REACH_CHUNK]
        corners = bounds[start : start + _REACH_CHUNK, _CORNER_BITS, axes]  # (n, 8, 3)
        world = np.einsum("nkj,nij->nki", corners, part[:, :, :3]) + part[:, None, :, 3]
        outside = ~(np.abs(world) <= MAX_COORDINATE).reshape(len(part), -1).all(1)
        if outside.any():
            i = int(np.flatnonzero(outside)[0])
            check_world_positions(world[i], name_of(start + i))  # raises, naming the instance
            raise ExportError(f"object '{name_of(start + i)}' reaches outside the supported coordinate range")
