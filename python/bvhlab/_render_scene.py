"""The scene in GPU layout (`_core.RenderScene`), made once per version of a tree, its geometry and
its materials, and kept by a Renderer (one SceneCache each), and by the traversal records
(inspect.ray_record: trace_pixel and the pick's rule), while they stay the same."""

from __future__ import annotations

import threading
from dataclasses import dataclass

import numpy as np

from . import _core
from .instanced import InstancedBvh
from .overlay_levels import traced_level, two_level_boxes
from .scene_parts import material_rows


def _array_key(a: np.ndarray) -> tuple:
    return a.shape, hash(a.tobytes())


@dataclass(frozen=True)
class _Parts:
    """What a RenderScene is made of, read from the Scene once: the cache's key and the scene it
    makes come from the same read (read twice, a material set on another thread between the two
    left a scene of the new materials under the old key, and renders in the wrong colours until
    the key changed again)."""

    triangles: tuple  # of each mesh (one: a flat scene)
    spheres: np.ndarray  # mesh 0's
    materials: tuple
    tri_material: tuple  # of each mesh
    sphere_material: np.ndarray

    @classmethod
    def of(cls, scene, two_level: bool) -> _Parts:
        meshes = range(scene.mesh_count) if two_level else range(1)
        return cls(
            tuple(scene.mesh_triangles(k) for k in meshes),
            scene.spheres,
            tuple(scene.materials),
            tuple(scene.mesh_triangle_material(k) for k in meshes),
            scene.sphere_material,
        )


class SceneCache:
    """Remembers the RenderScene last made and the key it was made for: the tree (object and
    revision, which refit bumps; for a two-level tree its TLAS object, which holds the meshes' tree
    versions), the geometry's fingerprint (so in-place edits of the arrays are seen) and the
    materials and every mesh's material indices (by value). And the copy last made of it whose
    overlay pass draws a two-level tree's BLAS boxes (RenderOptions.overlay_level), by (level,
    depth range)."""

    def __init__(self):
        self._lock = threading.Lock()
        self._key = None
        self._scene = None
        self._overlay_key = None
        self._overlay_scene = None

    def get(self, scene, bvh, options=None) -> _core.RenderScene:
        """The RenderScene of `scene` and `bvh`; `options` (RenderOptions) picks its overlay boxes."""
        two_level = isinstance(bvh, InstancedBvh)
        if two_level:
            bvh = bvh.snapshot()  # one TLAS for the key, the scene and its boxes (another thread may place)
        if scene.is_instanced and not two_level:
            raise ValueError("an instanced scene renders with its two-level tree: bvhlab.build(scene)")
        if two_level:
            _check_same_instances(scene, bvh)
        parts = _Parts.of(scene, two_level)
        key = self._key_of(parts, bvh, two_level)
        level = traced_level(bvh, options)
        with self._lock:
            if self._key != key:
                self._scene = self._overlay_scene = self._key = self._overlay_key = None  # the old go first
                self._scene, self._key = _make(parts, bvh, two_level), key
            render_scene = self._scene
            assert render_scene is not None  # made above for this key
            if level is None:
                return render_scene
            if self._overlay_key != (key, level):
                boxes = two_level_boxes(bvh, *level)
                self._overlay_scene = render_scene.with_overlay_boxes(boxes.lo, boxes.hi, boxes.depth)
                self._overlay_key = (key, level)
            return self._overlay_scene

    @staticmethod
    def _key_of(parts: _Parts, bvh, two_level: bool) -> tuple:
        spheres = [parts.spheres] + [None] * (len(parts.triangles) - 1)
        tree = bvh._core
        # a flat tree's snapshot (Bvh._snapshot: a fork sharing the version) keys as its tree at
        # that revision: the render scene made for one snapshot serves the next of the same version
        owner = getattr(bvh, "_source", bvh)._core if not two_level else tree
        return (
            owner,
            0 if two_level else tree.revision,
            tuple(_core.geometry_fingerprint(t, s) for t, s in zip(parts.triangles, spheres)),
            parts.materials,
            _array_key(parts.sphere_material),
            # every mesh's: a shared mesh whose faces changed material kept the old indices (one
            # Renderer for F12 and the viewport: 736 pixels of a linked duplicate stayed red)
            tuple(_array_key(m) for m in parts.tri_material),
        )


def _check_same_instances(scene, bvh: InstancedBvh) -> None:
    """A two-level tree renders the scene it was placed for. Its meshes' geometry is checked by
    fingerprint as a flat tree's is; its instances were not, so a scene whose instances moved,
    or a flat scene, rendered the tree's placement without a word (helper probe: 139 of 3,072
    pixels of a copy the flat scene does not have)."""
    if len(bvh.meshes) != scene.mesh_count:
        raise ValueError(f"the tree has {len(bvh.meshes)} meshes, the scene {scene.mesh_count}")
    mesh_of, transforms = scene.instances()
    placed_mesh, placed = bvh.instances
    if len(mesh_of) != len(placed_mesh):
        raise ValueError(f"the tree has {len(placed_mesh)} instances, the scene {len(mesh_of)}: build it again")
    if not (np.array_equal(mesh_of, placed_mesh) and np.array_equal(transforms, placed)):
        raise ValueError(
            "the tree's instances are not placed as the scene's: place them again "
            "(tree.place(*scene.instances())) or build again"
        )


def _make(parts: _Parts, bvh, two_level: bool) -> _core.RenderScene:
    if not two_level:
        return _core.RenderScene(
            bvh._core,
            parts.triangles[0],
            parts.spheres,
            material_rows(parts.materials),
            parts.tri_material[0],
            parts.sphere_material,
        )
    # The two-level tracer (issue 34): the meshes' own triangles, placed by the TLAS's instances;
    # the scene's spheres belong to mesh 0.
    n = len(parts.triangles)
    no_spheres = np.zeros(0, np.int32)
    return _core.RenderScene(
        bvh._core,
        list(parts.triangles),
        [parts.spheres if k == 0 else None for k in range(n)],
        material_rows(parts.materials),
        list(parts.tri_material),
        [parts.sphere_material if k == 0 else no_spheres for k in range(n)],
    )
