"""The checks of `bvhlab.Scene`'s fields, run each time a field is set (in the constructor and after
it), so a scene never holds a float64 array, a NaN vertex or a camera that is a tuple; each error
names the field (and the mesh, instance or primitive)."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from . import _checks, _core
from .scene_parts import Camera, Light, Material, _radiance

if TYPE_CHECKING:
    from .scene import Scene


def _triangles(scene: Scene, value) -> np.ndarray:
    value = _checks.float32_array("triangles", value, (3, 3))
    _core.validate_geometry(value, None)  # NaN, inf or out of range: names the triangle
    return value


def _spheres(scene: Scene, value) -> np.ndarray:
    value = _checks.float32_array("spheres", value, (4,))
    _core.validate_geometry(np.zeros((0, 3, 3), np.float32), value)
    return value


def _meshes(value) -> list[np.ndarray]:
    if isinstance(value, np.ndarray) or not isinstance(value, (list, tuple)):
        raise TypeError(f"meshes must be a list of float32 (T,3,3) triangle arrays, got {type(value).__name__}")
    out = []
    for k, m in enumerate(value, start=1):
        m = _checks.float32_array(f"mesh {k}", m, (3, 3))
        try:
            _core.validate_geometry(m, None)
        except ValueError as e:
            raise ValueError(f"mesh {k}: {e}") from None
        out.append(m)
    return out


def _mesh_tri_material(value) -> list[np.ndarray]:
    """One (T,) integer array per mesh 1..; checked against the meshes and materials when read
    (Scene.mesh_triangle_material), since either may be set after it."""
    if isinstance(value, np.ndarray) or not isinstance(value, (list, tuple)):
        raise TypeError(f"mesh_tri_material must be a list of (T,) integer arrays, got {type(value).__name__}")
    out = []
    for k, m in enumerate(value, start=1):
        m = np.asarray(m)
        if m.ndim != 1 or not (np.issubdtype(m.dtype, np.integer) or m.size == 0):
            raise ValueError(
                f"mesh_tri_material of mesh {k} must be (T,) integers, got shape {m.shape} dtype {m.dtype}"
            )
        out.append(_as_int32(m, f"mesh_tri_material of mesh {k}", "triangle", "material"))
    return out


def _as_int32(value: np.ndarray, name: str, item: str, target: str) -> np.ndarray:
    """Integer `value` as int32, refusing an entry int32 cannot hold (a cast would wrap 2^32 to 0,
    a silent reference to another mesh or material)."""
    lo, hi = np.iinfo(np.int32).min, np.iinfo(np.int32).max
    if value.size and value.dtype.itemsize >= 4 and (value.min() < lo or value.max() > hi):
        bad = int(np.flatnonzero((value < lo) | (value > hi))[0])
        raise ValueError(f"{name}: {item} {bad} refers to {target} {value[bad]}, which does not exist")
    return np.ascontiguousarray(value, np.int32)


def _instance_mesh(value) -> np.ndarray | None:
    if value is None:
        return None
    value = np.asarray(value)
    if value.ndim != 1 or not (np.issubdtype(value.dtype, np.integer) or value.size == 0):
        raise ValueError(f"instance_mesh must be (N,) integers, got shape {value.shape} dtype {value.dtype}")
    return _as_int32(value, "instance_mesh", "instance", "mesh")


def _instance_transforms(value) -> np.ndarray | None:
    if value is None:
        return None
    value = _checks.float32_array("instance_transforms", value, (3, 4))
    bad = np.flatnonzero(~np.isfinite(value).reshape(len(value), 12).all(1))  # 12, not -1: N may be 0
    if len(bad):
        raise ValueError(f"instance {bad[0]}: the transform has a NaN or infinite entry")
    return value


def _materials(scene: Scene, value) -> list[Material]:
    if value is None or (hasattr(value, "__len__") and len(value) == 0):
        return [Material()]
    if isinstance(value, (str, bytes, Material)) or not hasattr(value, "__iter__"):
        raise TypeError(f"materials must be a list of bvhlab.Material, got {type(value).__name__}")
    return [m if isinstance(m, Material) else Material(*m) for m in value]


def _instance_of(kind: type, name: str):
    def check(scene: Scene, value):
        if value is not None and not isinstance(value, kind):
            raise TypeError(
                f"{name} must be a bvhlab.{kind.__name__} or None, got {type(value).__name__} "
                f"{value!r:.60} (make one with bvhlab.{kind.__name__}(...))"
            )
        return value

    return check


FIELD_CHECKS = {
    "triangles": _triangles,
    "spheres": _spheres,
    "materials": _materials,
    "tri_material": lambda scene, v: scene._material_index("tri_material", v, len(scene.triangles)),
    "sphere_material": lambda scene, v: scene._material_index("sphere_material", v, len(scene.spheres)),
    "camera": _instance_of(Camera, "camera"),
    "light": _instance_of(Light, "light"),
    "sky": lambda scene, v: _radiance("sky", v),
    "meshes": lambda scene, v: _meshes(v),
    "mesh_tri_material": lambda scene, v: _mesh_tri_material(v),
    "instance_mesh": lambda scene, v: _instance_mesh(v),
    "instance_transforms": lambda scene, v: _instance_transforms(v),
}
