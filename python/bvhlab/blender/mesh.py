"""Evaluated mesh → world-space triangles, with bulk `foreach_get` into numpy (no per-vertex Python)."""
from __future__ import annotations

import numpy as np

from .errors import ExportError

#: Object types whose evaluated geometry converts to a mesh (curves with bevel, text, surfaces, metaballs).
CONVERTIBLE_TYPES = frozenset({"CURVE", "SURFACE", "FONT", "META"})


def gather_mesh_triangles(obj, matrix_world: np.ndarray, name: str):
    """World-space triangles of an evaluated object (modifiers applied) and, for each triangle, the
    index of its material slot. Returns (float32 (T,3,3), int32 (T,)); T may be 0.
    Raises ExportError naming the object when a vertex is NaN or infinite."""
    if obj.type == "MESH":
        return _mesh_triangles(obj.data, matrix_world, name)
    if obj.type not in CONVERTIBLE_TYPES:
        return np.zeros((0, 3, 3), np.float32), np.zeros(0, np.int32)
    mesh = obj.to_mesh()
    try:
        return _mesh_triangles(mesh, matrix_world, name)
    finally:
        obj.to_mesh_clear()


def _mesh_triangles(mesh, matrix_world: np.ndarray, name: str):
    if len(mesh.polygons) == 0:
        return np.zeros((0, 3, 3), np.float32), np.zeros(0, np.int32)
    positions = np.empty(len(mesh.vertices) * 3, np.float32)
    mesh.attributes["position"].data.foreach_get("vector", positions)
    positions = positions.reshape(-1, 3)
    finite = np.isfinite(positions)
    if not finite.all():
        bad = int(np.flatnonzero(~finite.all(1))[0])
        raise ExportError(f"object '{name}' has a vertex that is not a finite number (vertex {bad}: "
                          f"{tuple(float(x) for x in positions[bad])}); fix or delete it before building")
    corners, face_of_triangle = _loop_triangles(mesh)
    # Transform the vertices (fewer than 3 per triangle) before gathering them into triangles.
    linear, offset = matrix_world[:3, :3].astype(np.float32), matrix_world[:3, 3].astype(np.float32)
    with np.errstate(over="ignore", invalid="ignore"):
        world = positions @ linear.T + offset
    check_world_positions(world, name)
    return world[corners].reshape(-1, 3, 3), _triangle_material_slots(mesh, face_of_triangle)


def check_world_positions(world: np.ndarray, name: str) -> None:
    """Raises ExportError naming the object when a world-space point is NaN (a NaN location,
    rotation or scale) or lies outside ±MAX_COORDINATE, where bvhlab's float32 ray tests would
    overflow (Blender stores an infinite coordinate as ±3.4e38: it lands here too)."""
    from ..scene import MAX_COORDINATE

    inside = np.abs(world) <= MAX_COORDINATE  # False for NaN
    if inside.all():
        return
    bad = int(np.flatnonzero(~inside.all(1))[0])
    where = f"vertex {bad} at {tuple(float(x) for x in world[bad])}"
    if np.isnan(world[bad]).any():
        raise ExportError(f"object '{name}' has a vertex that is not a number in world space ({where}): check its "
                          "location, rotation and scale, and its parents'")
    raise ExportError(f"object '{name}' reaches outside the supported coordinate range ±{MAX_COORDINATE:.5g} (2^40) "
                      f"({where}): move or scale it nearer the origin")


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
