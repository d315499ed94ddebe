"""The scene in GPU layout (`_core.RenderScene`), made once per version of a tree, its geometry and
its materials, and kept by a Renderer (one SceneCache each) while they stay the same."""

from __future__ import annotations

import threading

import numpy as np

from . import _core


def _array_key(a: np.ndarray) -> tuple:
    return a.shape, hash(a.tobytes())


class SceneCache:
    """Remembers the RenderScene last made and the key it was made for: the tree (object and
    revision, which refit bumps), the geometry's fingerprint (so in-place edits of the arrays are
    seen) and the materials (by value)."""

    def __init__(self):
        self._lock = threading.Lock()
        self._key = None
        self._scene = None

    def get(self, scene, bvh) -> _core.RenderScene:
        if scene.is_instanced:  # the tracer walks one level (issue 34 leaves the two-level tracer to come)
            raise ValueError("the renderers take flat scenes: render scene.flattened() with a tree built over it")
        tree = bvh._core
        fingerprint = _core.geometry_fingerprint(scene.triangles, scene.spheres)
        key = (
            tree,
            tree.revision,
            fingerprint,
            tuple(scene.materials),
            _array_key(scene.tri_material),
            _array_key(scene.sphere_material),
        )
        with self._lock:
            if self._key == key:
                return self._scene
            render_scene = _core.RenderScene(
                tree, scene.triangles, scene.spheres, scene.material_table(), scene.tri_material, scene.sphere_material
            )
            self._key, self._scene = key, render_scene
            return render_scene
