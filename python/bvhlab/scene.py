"""`bvhlab.Scene`: geometry (meshes, spheres, instances), materials, camera, light and sky as numpy
arrays, saved as `.npz`. Its parts besides geometry are in scene_parts.py, the checks of its fields
in scene_checks.py, its file format in scene_file.py."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ._npz import MAX_EXPANSION, SceneFileError
from .scene_checks import FIELD_CHECKS
from .scene_file import FORMAT_VERSION, READ_FORMAT_VERSIONS, read_scene, write_scene
from .scene_parts import (
    DEFAULT_SKY,
    LENS_ROW,
    MAX_COORDINATE,
    Camera,
    Lens,
    Light,
    Material,
    View,
    default_camera,
    default_light,
    material_rows,
)

__all__ = [
    "DEFAULT_SKY",
    "FORMAT_VERSION",
    "LENS_ROW",
    "MAX_COORDINATE",
    "READ_FORMAT_VERSIONS",
    "Camera",
    "Lens",
    "Light",
    "Material",
    "Scene",
    "SceneFileError",
    "View",
    "default_camera",
    "default_light",
]


#: Each kind of primitive's material index field.
_INDICES = {"triangles": "tri_material", "spheres": "sphere_material"}


@dataclass
class Scene:
    """What bvhlab builds and renders. Missing parts get defaults that make a two-line script work:
    a camera framing the bounds (45° vertical, from the front-upper diagonal, Z up), a point light
    near it, matte white materials and a soft blue sky."""

    triangles: np.ndarray = field(default_factory=lambda: np.zeros((0, 3, 3), np.float32))
    spheres: np.ndarray = field(default_factory=lambda: np.zeros((0, 4), np.float32))
    materials: list[Material] = field(default_factory=lambda: [Material()])
    # None in the constructor means material 0 for all; the field always holds an int32 array.
    tri_material: np.ndarray = None  # type: ignore[assignment]
    sphere_material: np.ndarray = None  # type: ignore[assignment]
    camera: Camera | None = None
    light: Light | None = None
    sky: tuple[float, float, float] = DEFAULT_SKY
    # Instancing (issue 34; bvhlab.instanced). The scene's own triangles and spheres are mesh 0;
    # `meshes` adds meshes 1, 2, ... (float32 (T,3,3) triangle arrays); `mesh_tri_material`, when
    # given, holds the material index of each of their triangles (one int32 array per mesh; empty:
    # material 0 for all, as before; the Blender exporter fills it). Instance i places
    # mesh instance_mesh[i] by instance_transforms[i] (float32 (3,4), object to world, row-major).
    # Without instances every mesh is placed once where it was modelled: Scene(triangles=...) is
    # one mesh and one identity instance, the flat scene of before.
    meshes: list[np.ndarray] = field(default_factory=list)
    mesh_tri_material: list[np.ndarray] = field(default_factory=list)
    instance_mesh: np.ndarray | None = None
    instance_transforms: np.ndarray | None = None

    def __setattr__(self, name, value):
        # Every field is checked when it is set, in the constructor and after it, so a scene never
        # holds a float64 array, a NaN vertex or a camera that is a tuple (the error names the field).
        check = FIELD_CHECKS.get(name)
        object.__setattr__(self, name, check(self, value) if check else value)
        # material indices never given (material 0 for all) follow their geometry: a scene made of
        # triangles alone and given others (`scene.triangles = next_frame`) kept indices of the old
        # count, built, and then failed to render, and saved a file that would not load (a copy of
        # the scene keeps the set of its own: replaced, never changed in place)
        defaulted = self.__dict__.get("_defaulted_indices", frozenset())
        if name in _INDICES.values():
            defaulted = defaulted | {name} if value is None else defaulted - {name}
            object.__setattr__(self, "_defaulted_indices", defaulted)
        elif _INDICES.get(name) in defaulted:
            object.__setattr__(self, _INDICES[name], np.zeros(len(getattr(self, name)), np.int32))

    def __post_init__(self):
        if self.camera is None:
            self.camera = self._framing_camera()
        if self.light is None and self.camera is not None:
            self.light = default_light(self.camera)

    def _framing_camera(self) -> Camera | None:
        """The default camera (`default_camera` of the world's bounds); None when there is nothing
        to frame (no geometry, or no instance of a mesh with any), or when the geometry reaches so
        near ±MAX_COORDINATE that a camera framing it would stand outside the coordinate range
        (valid geometry all the same: it builds and takes rays; `render` asks for a camera)."""
        if not (self.primitive_count or any(len(m) for m in self.meshes)):
            return None
        bounds = self.world_bounds()
        if bounds is None:
            return None
        try:
            return default_camera(bounds)
        except ValueError:  # the Camera's own check refused where it would stand
            return None

    def _material_index(self, name: str, value, n: int) -> np.ndarray:
        if value is None:
            return np.zeros(n, np.int32)
        value = np.asarray(value)
        if n == 0 and value.size == 0:
            return np.zeros(0, np.int32)
        if value.shape != (n,) or not np.issubdtype(value.dtype, np.integer):
            raise ValueError(f"{name} must be {n} integers, got shape {value.shape} dtype {value.dtype}")
        if n and (value.min() < 0 or value.max() >= len(self.materials)):
            raise ValueError(f"{name} refers to a material that does not exist (have {len(self.materials)})")
        return value.astype(np.int32)

    @property
    def primitive_count(self) -> int:
        """Primitives of the scene's own geometry (mesh 0)."""
        return len(self.triangles) + len(self.spheres)

    @property
    def has_geometry(self) -> bool:
        """Whether any primitive is placed in the world: mesh 0's where the scene is flat, else an
        instance of a mesh that has some (an instanced scene's own geometry may be empty and its
        instances not: Blender's linked duplicates alone export so)."""
        if not self.is_instanced:
            return bool(self.primitive_count)
        mesh_of, _ = self.instances()
        sizes = np.array([self.primitive_count, *(len(m) for m in self.meshes)])
        return bool((sizes[mesh_of] > 0).any())

    # -- instancing ----------------------------------------------------------------------------
    @property
    def is_instanced(self) -> bool:
        """True when the scene has meshes besides its own or instances given: bvhlab.build then
        makes a two-level tree (bvhlab.InstancedBvh)."""
        return bool(self.meshes) or self.instance_mesh is not None or self.instance_transforms is not None

    @property
    def mesh_count(self) -> int:
        return 1 + len(self.meshes)

    def mesh_triangles(self, k: int) -> np.ndarray:
        """The triangles of mesh k (0: the scene's own)."""
        return self.triangles if k == 0 else self.meshes[k - 1]

    def mesh_triangle_material(self, k: int) -> np.ndarray:
        """The material index of each triangle of mesh k: the scene's own (mesh 0) keep
        tri_material, the other meshes theirs in mesh_tri_material (material 0 when it is empty).
        Raises ValueError when mesh_tri_material does not match the meshes or the materials."""
        if k == 0:
            return self.tri_material
        triangles = self.meshes[k - 1]
        if not self.mesh_tri_material:
            return np.zeros(len(triangles), np.int32)
        if len(self.mesh_tri_material) != len(self.meshes):
            raise ValueError(
                f"mesh_tri_material has {len(self.mesh_tri_material)} arrays for {len(self.meshes)} meshes"
            )
        return self._material_index(f"mesh_tri_material of mesh {k}", self.mesh_tri_material[k - 1], len(triangles))

    def instances(self) -> tuple[np.ndarray, np.ndarray]:
        """(mesh index int32 (N,), object-to-world float32 (N,3,4)): the instances given, checked
        against each other and the meshes (ValueError naming the instance), or every mesh once
        where it was modelled."""
        if self.instance_mesh is None and self.instance_transforms is None:
            n = self.mesh_count
            return np.arange(n, dtype=np.int32), np.ascontiguousarray(np.tile(_IDENTITY, (n, 1, 1)))
        if self.instance_mesh is None or self.instance_transforms is None:
            raise ValueError("instance_mesh and instance_transforms are given together (one each per instance)")
        mesh, transforms = self.instance_mesh, self.instance_transforms
        if len(mesh) != len(transforms):
            raise ValueError(f"{len(mesh)} instance meshes but {len(transforms)} instance transforms")
        bad = np.flatnonzero((mesh < 0) | (mesh >= self.mesh_count))
        if len(bad):
            raise ValueError(
                f"instance {bad[0]} refers to mesh {mesh[bad[0]]}, but the scene has {self.mesh_count} "
                f"mesh{'es' if self.mesh_count != 1 else ''}"
            )
        return mesh, transforms

    def flattened(self) -> Scene:
        """The same geometry as one flat mesh: every instance's triangles moved into the world (the
        flat scene that a two-level tree must agree with). Spheres of mesh 0 move with its
        instances, which must then keep them spheres (rotation, uniform scale, translation). Each
        triangle keeps its vertices' order, so a hit's u, v are the two-level walk's: a mirrored
        instance's triangles then wind the other way from the Blender export's instancing=False
        (which reverses them); every shading of bvhlab is two-sided."""
        if not self.is_instanced:
            return self
        mesh_of, transforms = self.instances()
        tris, tri_mat, spheres, sphere_mat = [], [], [], []
        for k, t in zip(mesh_of, transforms.astype(np.float64)):
            src = self.mesh_triangles(int(k)).astype(np.float64)
            tris.append((src @ t[:, :3].T + t[:, 3]).astype(np.float32))
            tri_mat.append(self.mesh_triangle_material(int(k)))
            if k == 0 and len(self.spheres):
                spheres.append(_moved_spheres(self.spheres, t))
                sphere_mat.append(self.sphere_material)
        return Scene(
            triangles=np.ascontiguousarray(np.concatenate(tris or [np.zeros((0, 3, 3), np.float32)])),
            spheres=np.ascontiguousarray(np.concatenate(spheres or [np.zeros((0, 4), np.float32)])),
            materials=list(self.materials),
            tri_material=np.concatenate(tri_mat or [np.zeros(0, np.int32)]),
            sphere_material=np.concatenate(sphere_mat or [np.zeros(0, np.int32)]),
            camera=self.camera,
            light=self.light,
            sky=self.sky,
        )

    def _mesh_bounds(self, k: int) -> tuple[np.ndarray, np.ndarray] | None:
        parts_lo, parts_hi = [], []
        tris = self.mesh_triangles(k)
        if len(tris):
            points = tris.reshape(-1, 3)
            # one column at a time: numpy reduces contiguous columns several times faster
            parts_lo.append(np.array([points[:, c].min() for c in range(3)]))
            parts_hi.append(np.array([points[:, c].max() for c in range(3)]))
        if k == 0 and len(self.spheres):
            parts_lo.append((self.spheres[:, :3] - self.spheres[:, 3:]).min(0))
            parts_hi.append((self.spheres[:, :3] + self.spheres[:, 3:]).max(0))
        if not parts_lo:
            return None
        return np.min(parts_lo, 0), np.max(parts_hi, 0)

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """(lo, hi) of all primitives (of every instance, in the world); raises ValueError for an
        empty scene."""
        box = self.world_bounds()
        if box is None:
            raise ValueError("the scene has no geometry")
        return box

    def world_bounds(self) -> tuple[np.ndarray, np.ndarray] | None:
        """`bounds()`, or None for a scene with no geometry in the world."""
        return self._instanced_bounds() if self.is_instanced else self._mesh_bounds(0)

    def _instanced_bounds(self) -> tuple[np.ndarray, np.ndarray] | None:
        # each instance's world box from its mesh's box at once (centre moved, half-extent by |A|:
        # the box of the moved corners; Arvo 1990), not a Python loop over a million instances
        mesh_of, transforms = self.instances()
        boxes = [self._mesh_bounds(k) for k in range(self.mesh_count)]
        has = np.array([b is not None for b in boxes])
        keep = has[mesh_of] if len(mesh_of) else np.zeros(0, bool)
        if not keep.any():
            return None
        lo = np.array([b[0] if b is not None else np.zeros(3) for b in boxes], np.float64)
        hi = np.array([b[1] if b is not None else np.zeros(3) for b in boxes], np.float64)
        k = mesh_of[keep]
        t = transforms[keep].astype(np.float64)
        centre = np.einsum("nij,nj->ni", t[:, :, :3], (lo[k] + hi[k]) / 2) + t[:, :, 3]
        half = np.einsum("nij,nj->ni", np.abs(t[:, :, :3]), (hi[k] - lo[k]) / 2)
        return (centre - half).min(0), (centre + half).max(0)

    def material_table(self) -> np.ndarray:
        """float32 (M, 8): r, g, b, reflective, transparent, ior, holdout (0 or 1), the bits of the rays
        it is hidden from (Material.hidden_from)."""
        return material_rows(self.materials)

    # -- files (scene_file.py) ------------------------------------------------------------------
    def save(self, path) -> Path:
        """Write an `.npz` (no pickled objects) that `Scene.load` and the CLI read, exactly at `path`,
        which must end in .npz (never renamed); an existing file is replaced only once the new one
        is complete. Returns the path."""
        return write_scene(self, path)

    @classmethod
    def load(cls, path, *, max_expansion: float = MAX_EXPANSION) -> Scene:
        """Read a scene written by `save`. Headers are checked before data is read: dtypes, shapes,
        counts that agree, and no more than `max_expansion` times the file's size once over 64 MiB
        (a small crafted file cannot claim gigabytes). Raises FileNotFoundError, or SceneFileError
        (a ValueError) naming the file and the problem."""
        return read_scene(cls, path, max_expansion=max_expansion)


_IDENTITY = np.array([[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0]], np.float32)


def _moved_spheres(spheres: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Spheres under a transform that keeps them spheres (its linear part a scaled rotation)."""
    a = t[:, :3]
    gram = a.T @ a
    scale2 = gram[0, 0]
    if not np.allclose(gram, scale2 * np.eye(3), rtol=1e-5, atol=1e-6 * max(scale2, 1e-30)):
        raise ValueError("an instance of mesh 0 with spheres must keep them spheres (rotation, uniform scale)")
    centres = spheres[:, :3].astype(np.float64) @ a.T + t[:, 3]
    radii = spheres[:, 3:].astype(np.float64) * np.sqrt(scale2)
    return np.concatenate([centres, radii], 1).astype(np.float32)
