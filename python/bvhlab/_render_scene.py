"""The scene in GPU layout (`_core.RenderScene`), made once per version of a tree, its geometry and
its materials, and kept by a Renderer (one SceneCache each) while they stay the same."""

from __future__ import annotations

import threading

import numpy as np

from . import _core
from .instanced import InstancedBvh
from .overlay_levels import traced_level, two_level_boxes


def _array_key(a: np.ndarray) -> tuple:
    return a.shape, hash(a.tobytes())


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
        if two_level and len(bvh.meshes) != scene.mesh_count:
            raise ValueError(f"the tree has {len(bvh.meshes)} meshes, the scene {scene.mesh_count}")
        key = self._key_of(scene, bvh, two_level)
        level = traced_level(bvh, options)
        with self._lock:
            if self._key != key:
                self._scene = self._overlay_scene = self._key = self._overlay_key = None  # the old go first
                self._scene, self._key = _make(scene, bvh, two_level), key
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
    def _key_of(scene, bvh, two_level: bool) -> tuple:
        meshes = range(scene.mesh_count) if two_level else range(1)
        spheres = [scene.spheres if k == 0 else None for k in meshes]
        tree = bvh._core
        return (
            tree,
            0 if two_level else tree.revision,
            tuple(_core.geometry_fingerprint(scene.mesh_triangles(k), s) for k, s in zip(meshes, spheres)),
            tuple(scene.materials),
            _array_key(scene.tri_material),
            _array_key(scene.sphere_material),
            # the other meshes' too: a shared mesh whose faces changed material kept the old indices
            # (one Renderer for F12 and the viewport: 736 pixels of a linked duplicate stayed red)
            tuple(_array_key(scene.mesh_triangle_material(k)) for k in meshes if k > 0),
        )


def _make(scene, bvh, two_level: bool) -> _core.RenderScene:
    if not two_level:
        return _core.RenderScene(
            bvh._core, scene.triangles, scene.spheres, scene.material_table(), scene.tri_material, scene.sphere_material
        )
    # The two-level tracer (issue 34): the meshes' own triangles, placed by the TLAS's instances;
    # the scene's spheres belong to mesh 0.
    n = scene.mesh_count
    no_spheres = np.zeros(0, np.int32)
    return _core.RenderScene(
        bvh._core,
        [scene.mesh_triangles(k) for k in range(n)],
        [scene.spheres if k == 0 else None for k in range(n)],
        scene.material_table(),
        [scene.mesh_triangle_material(k) for k in range(n)],
        [scene.sphere_material if k == 0 else no_spheres for k in range(n)],
    )
