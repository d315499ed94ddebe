"""Evaluated mesh → world-space triangles, with bulk `foreach_get` into numpy (no per-vertex Python).

Reading (`read_mesh`: object-space vertices, triangle corners, material slots) is kept apart from
placing (`MeshData.world_triangles`), so a scene kept between frames (`live.LiveScene`) reads a
mesh again only when its geometry changed and only re-places it when the object moved."""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from .errors import ExportError

#: Object types whose evaluated geometry converts to a mesh (curves with bevel, text, surfaces, metaballs).
CONVERTIBLE_TYPES = frozenset({"CURVE", "SURFACE", "FONT", "META"})


@dataclass(frozen=True)
class MeshData:
    """One evaluated mesh as read from Blender: float32 object-space vertices (V,3), int32 vertex
    index of each triangle corner (3T,), int32 material slot of each triangle (T,)."""

    positions: np.ndarray
    corners: np.ndarray
    slots: np.ndarray

    @property
    def triangle_count(self) -> int:
        return len(self.slots)

    def same_as(self, other: MeshData) -> bool:
        """The same vertices, triangles and slots (a mesh read again, where Blender named an
        object's geometry though it did not change: a setting's update, a material's under 5.3)."""
        return self is other or (
            np.array_equal(self.positions, other.positions)
            and np.array_equal(self.corners, other.corners)
            and np.array_equal(self.slots, other.slots)
        )

    @cached_property
    def triangles(self) -> np.ndarray:
        """float32 (T,3,3) object-space triangles (a shared mesh's, placed by its instances); made
        once per MeshData."""
        return np.ascontiguousarray(self.positions[self.corners].reshape(-1, 3, 3))

    @cached_property
    def bounds(self) -> np.ndarray:
        """float64 (2,3) object-space box of the vertices the triangles use."""
        used = self.positions[self.corners].astype(np.float64)
        return np.stack([used.min(0), used.max(0)])

    def world_triangles(self, matrix_world: np.ndarray, name: str) -> np.ndarray:
        """float32 (T,3,3) world-space triangles. The vertices (fewer than 3 per triangle) are
        transformed before they are gathered into triangles. A mirroring matrix (negative
        determinant) gets each triangle's winding reversed, so that the geometric normal still points
        out, as Blender shows a mirrored object (and as the tracers shade a mirrored instance: issue
        34). Raises ExportError naming the object when a transformed vertex is NaN or outside the
        supported range (check_world_positions)."""
        if not len(self.slots):
            return np.zeros((0, 3, 3), np.float32)
        linear, offset = matrix_world[:3, :3].astype(np.float32), matrix_world[:3, 3].astype(np.float32)
        with np.errstate(over="ignore", invalid="ignore"):
            world = self.positions @ linear.T + offset
        check_world_positions(world, name, self.corners)
        corners = self.corners
        if np.linalg.det(matrix_world[:3, :3]) < 0:
            corners = corners.reshape(-1, 3)[:, ::-1].reshape(-1)
        return world[corners].reshape(-1, 3, 3)


EMPTY_MESH = MeshData(np.zeros((0, 3), np.float32), np.zeros(0, np.int32), np.zeros(0, np.int32))


def gather_mesh_triangles(obj, matrix_world: np.ndarray, name: str):
    """World-space triangles of an evaluated object (modifiers applied) and, for each triangle, the
    index of its material slot. Returns (float32 (T,3,3), int32 (T,)); T may be 0.
    Raises ExportError naming the object when a vertex is NaN or infinite."""
    data = read_mesh(obj, name)
    return data.world_triangles(matrix_world, name), data.slots


def read_mesh(obj, name: str) -> MeshData:
    """The evaluated geometry of an object in its own space (EMPTY_MESH for objects without any).
    Raises ExportError naming the object when a vertex is NaN or infinite.

    A mesh in Edit Mode is read through to_mesh, as curves are: its evaluated `data` is Blender's
    wrapper of the edit mesh, whose polygons are empty until converted (the object would
    otherwise be left out, where Cycles renders it with the edits so far) and which has no
    attributes under 4.2 (KeyError 'position'). So is a linked duplicate of it, whose own mode is
    Object Mode (`data.is_editmode` says it; the probe: one of two boxes was left out under 4.5,
    the export failed under 4.2)."""
    if obj.type == "MESH" and obj.mode != "EDIT" and not getattr(obj.data, "is_editmode", False):
        return _read(obj.data, name)
    if obj.type != "MESH" and obj.type not in CONVERTIBLE_TYPES:
        return EMPTY_MESH
    mesh = obj.to_mesh()
    try:
        # None for a curve that geometry nodes put out on a mesh object (an instance of type CURVE,
        # with no surface): nothing to read, and Cycles renders nothing of it either
        return _read(mesh, name) if mesh is not None else EMPTY_MESH
    finally:
        obj.to_mesh_clear()


def _read(mesh, name: str) -> MeshData:
    if len(mesh.polygons) == 0:
        return EMPTY_MESH
    positions = np.empty(len(mesh.vertices) * 3, np.float32)
    mesh.attributes["position"].data.foreach_get("vector", positions)
    positions = positions.reshape(-1, 3)
    corners, face_of_triangle = _loop_triangles(mesh)
    finite = np.isfinite(positions).all(1)
    if not finite.all():
        bad = _first_used(~finite, corners)
        if bad is not None:
            raise ExportError(
                f"object '{name}' has a vertex that is not a finite number (vertex {bad}: "
                f"{tuple(float(x) for x in positions[bad])}); fix or delete it before building"
            )
        # only vertices in no face (loose ones, which Cycles does not render either): read as the
        # origin, so that no later pass over every vertex meets a NaN
        positions[~finite] = 0.0
    return MeshData(positions, corners, _triangle_material_slots(mesh, face_of_triangle))


def _first_used(flagged: np.ndarray, corners: np.ndarray) -> int | None:
    """The first vertex among `flagged` (bool per vertex) that a triangle uses (`corners`), or None
    where only vertices in no triangle are (a loose vertex far away or not a number must not refuse
    a mesh that renders without it)."""
    used = np.zeros(len(flagged), bool)
    used[corners] = True
    bad = np.flatnonzero(flagged & used)
    return int(bad[0]) if len(bad) else None


def check_world_positions(world: np.ndarray, name: str, corners: np.ndarray | None = None) -> None:
    """Raises ExportError naming the object when a world-space point is NaN (a NaN location,
    rotation or scale) or lies outside ±MAX_COORDINATE, where bvhlab's float32 ray tests would
    overflow (Blender stores an infinite coordinate as ±3.4e38: it lands here too). `corners`:
    only the points triangles use count (a mesh's loose vertices are not rendered)."""
    from ..scene import MAX_COORDINATE

    inside = (np.abs(world) <= MAX_COORDINATE).all(1)  # False for NaN
    if inside.all():
        return
    bad = _first_used(~inside, corners) if corners is not None else int(np.flatnonzero(~inside)[0])
    if bad is None:
        return
    where = f"vertex {bad} at {tuple(float(x) for x in world[bad])}"
    if np.isnan(world[bad]).any():
        raise ExportError(
            f"object '{name}' has a vertex that is not a number in world space ({where}): check its "
            "location, rotation and scale, and its parents'"
        )
    raise ExportError(
        f"object '{name}' reaches outside the supported coordinate range ±{MAX_COORDINATE:.5g} (2^40) "
        f"({where}): move or scale it nearer the origin"
    )


def _loop_triangles(mesh):
    """Vertex index of each triangle corner (3T,) and the face of each triangle (T,), from Blender's
    own triangulation (cached on evaluated meshes)."""
    mesh.calc_loop_triangles()
    count = len(mesh.loop_triangles)
    corners = np.empty(count * 3, np.int32)
    mesh.loop_triangles.foreach_get("vertices", corners)
    face_of_triangle = np.empty(count, np.int32)
    mesh.loop_triangle_polygons.foreach_get("value", face_of_triangle)
    return corners, face_of_triangle


def _triangle_material_slots(mesh, face_of_triangle: np.ndarray) -> np.ndarray:
    attribute = mesh.attributes.get("material_index")
    if attribute is None:
        return np.zeros(len(face_of_triangle), np.int32)
    per_face = np.empty(len(mesh.polygons), np.int32)
    attribute.data.foreach_get("value", per_face)
    return per_face[face_of_triangle]
