"""The add-on's one cache of trees (issue 38): the sidebar's Build, its Render and Export, F12 and
the Rendered viewport all take the tree of a (scene, scope, build settings) from here, so a tree
built by one is used by the others (Build, then F12: one build). Each `SceneTree` fits its tree to
the geometry it is given one way: kept when the arrays are the same (or equal), refit when only
positions moved (LiveScene's report says so, and the refit tree's SAH stays within REFIT_LIMIT of
the built one), built otherwise. An instanced scene (issue 34: F12 renders Blender's instancing
as instances) gets a two-level tree (bvhlab.InstancedBvh) under a key of its own
(`TreeKey.instanced`): the meshes' trees whose arrays are unchanged are kept, the others built,
and the TLAS made again over the instances ("placed" when only instances moved).

Trees are shared between threads (Blender's UI thread, its render thread, the viewport's worker):
a SceneTree is updated under its own lock, and a Bvh refit in place leaves the versions that
renders in flight hold intact (the core's immutable tree versions), so a reader never needs it."""

from __future__ import annotations

import threading
import time
from collections import OrderedDict
from dataclasses import dataclass

import numpy as np

from bvhlab.bvh import BuildConfig

#: A refit keeps the topology; once objects have moved far, its boxes overlap and tracing slows.
#: Rebuild instead when the refit tree's SAH cost exceeds the built tree's by this factor.
REFIT_LIMIT = 1.5
#: Trees kept per scene (the least recently used go first): a user trying a few settings back and
#: forth keeps each; a long comparison does not fill memory.
MAX_TREES_PER_SCENE = 3


@dataclass(frozen=True)
class TreeKey:
    """What a tree depends on besides the geometry: the scene (session_uid), the objects in it
    (scope), the build settings (BuildConfig compares without `threads`) and whether it is the
    two-level tree of the instanced scene (F12) or a flat one (the sidebar, the viewport: they
    take flat trees only and are given `Scene.flattened()` for now)."""

    scene: int
    scope: str
    config: BuildConfig
    instanced: bool = False


@dataclass(frozen=True)
class TreeUpdate:
    """What `SceneTree.update` did: "built", "refit", "placed" (a new TLAS over the same meshes'
    trees) or "kept", how long it took, and the Bvh (or InstancedBvh) that fits the scene it was
    given (use this one: another thread may update the SceneTree next)."""

    action: str
    bvh: object
    ms: float = 0.0


class SceneTree:
    """A Bvh over the geometry last given to `update` or `store`, built with `config`."""

    #: Builds by every SceneTree (the tests count them: Build, then F12, must build once).
    builds = 0
    _count_lock = threading.Lock()

    def __init__(self, config: BuildConfig):
        self.config = config
        self.bvh = None
        self.lock = threading.Lock()
        self._source: tuple = (None, None)  # the triangle and sphere arrays the tree is over
        self._built_sah = 0.0
        self.generation = 0  # counts the trees it has held (builds and refits)

    def update(self, scene, refittable: bool = False, progress=None, threads: int = 0) -> TreeUpdate:
        """Make the tree fit `scene` (a bvhlab.Scene). `refittable`: the primitives are those the
        tree was made over, in the same order, only moved (LiveScene's report). `progress(fraction)`
        returning False cancels a build (bvhlab.BuildCancelled). `threads`:
        for a build (0: all)."""
        with self.lock:
            start = time.perf_counter()
            if scene.is_instanced:
                action = self._update_instanced(scene, progress, threads)
                return TreeUpdate(action, self.bvh, 0.0 if action == "kept" else (time.perf_counter() - start) * 1e3)
            if self.bvh is not None and not isinstance(self.bvh, _instanced_type()):
                if self._same_geometry(scene):
                    self._source = (scene.triangles, scene.spheres)
                    return TreeUpdate("kept", self.bvh)
                if refittable and self._refit(scene):
                    return TreeUpdate("refit", self.bvh, (time.perf_counter() - start) * 1e3)
            self._build(scene, progress, threads)
            return TreeUpdate("built", self.bvh, (time.perf_counter() - start) * 1e3)

    def _update_instanced(self, scene, progress, threads: int) -> str:
        """Fit a two-level tree to an instanced scene: mesh k's tree is kept when its triangles (and
        mesh 0's spheres) are the arrays (or equal to those) it was built over, built otherwise;
        then the TLAS over the scene's instances, unless they are the same too."""
        import bvhlab

        sources = [(scene.mesh_triangles(k), scene.spheres if k == 0 else None) for k in range(scene.mesh_count)]
        mesh_of, transforms = scene.instances()
        old = self.bvh if isinstance(self.bvh, bvhlab.InstancedBvh) else None
        old_sources, old_instances = self._source if old is not None else ([], (None, None))
        trees, built = [], 0
        for k, (triangles, spheres) in enumerate(sources):
            if k < len(old_sources) and _same_arrays(old_sources[k], (triangles, spheres)):
                trees.append(old.meshes[k])
                continue
            part = None if progress is None else (lambda f, k=k: progress((k + f) / len(sources)))
            config = self.config.replace(threads=threads)
            mesh = bvhlab.Scene(triangles=triangles) if spheres is None else bvhlab.Scene(triangles, spheres)
            trees.append(bvhlab.build(mesh, config=config, progress=part))
            built += 1
        if old is not None and not built and len(trees) == len(old.meshes):
            if _same_arrays(old_instances, (mesh_of, transforms)):
                self._source = (sources, (mesh_of, transforms))
                return "kept"
        bvh = bvhlab.InstancedBvh(trees, mesh_of, transforms, self.config.replace(threads=threads))
        self.generation += 1
        self.bvh, self._source = bvh, (sources, (mesh_of, transforms))
        self._built_sah = bvh.stats["tlas_sah_cost"]
        if built:
            _count_build()
            return "built"
        return "placed"

    def store(self, bvh, scene) -> None:
        """A tree built elsewhere with this config over `scene` (the sidebar's Build, on its thread)."""
        with self.lock:
            self._keep(bvh, scene)
        _count_build()

    def _same_geometry(self, scene) -> bool:
        triangles, spheres = self._source
        if triangles is scene.triangles and spheres is scene.spheres:
            return True
        return (
            triangles is not None
            and np.array_equal(triangles, scene.triangles)
            and np.array_equal(spheres, scene.spheres)
        )

    def _refit(self, scene) -> bool:
        triangles, spheres = self._source
        if triangles is None or len(triangles) != len(scene.triangles) or len(spheres) != len(scene.spheres):
            return False
        try:
            self.bvh.refit(scene.triangles, scene.spheres)
        except ValueError:  # not the geometry the tree was built over after all: build instead
            return False
        self.generation += 1
        self._source = (scene.triangles, scene.spheres)
        return self.bvh.stats["sah_cost"] <= REFIT_LIMIT * self._built_sah

    def _build(self, scene, progress, threads: int) -> None:
        import bvhlab

        # A cancelled build keeps the tree before (a reader may hold it); its source stays the old
        # geometry, so the next update builds again.
        self._keep(bvhlab.build(scene, config=self.config.replace(threads=threads), progress=progress), scene)
        _count_build()

    def _keep(self, bvh, scene) -> None:
        self.generation += 1
        self.bvh = bvh
        self._source = (scene.triangles, scene.spheres)
        self._built_sah = bvh.stats["sah_cost"]


def _same_arrays(a: tuple, b: tuple) -> bool:
    return all(x is y or (x is not None and y is not None and np.array_equal(x, y)) for x, y in zip(a, b))


def _instanced_type() -> type:
    import bvhlab

    return bvhlab.InstancedBvh


def _count_build() -> None:
    with SceneTree._count_lock:
        SceneTree.builds += 1


class TreeCache:
    """SceneTrees by TreeKey, at most MAX_TREES_PER_SCENE per scene."""

    def __init__(self):
        self._lock = threading.Lock()
        self._trees: OrderedDict[TreeKey, SceneTree] = OrderedDict()

    def tree(self, key: TreeKey) -> SceneTree:
        """The key's SceneTree (new and empty the first time)."""
        with self._lock:
            tree = self._trees.get(key)
            if tree is None:
                tree = self._trees[key] = SceneTree(key.config)
                same_scene = [k for k in self._trees if k.scene == key.scene]
                for old in same_scene[:-MAX_TREES_PER_SCENE]:
                    del self._trees[old]  # whoever holds it keeps it; the cache forgets it
            self._trees.move_to_end(key)
            return tree

    def clear(self) -> None:
        with self._lock:
            self._trees.clear()


cache = TreeCache()


def key_of(blender_scene, scope: str | None = None, instanced: bool = False) -> TreeKey:
    """The key of the tree the scene's settings (scene.bvhlab) ask for; `scope`: the objects in it
    when not the settings' (the render engine always renders the visible ones); `instanced`: the
    two-level tree of an instanced scene (F12)."""
    settings = blender_scene.bvhlab
    return TreeKey(blender_scene.session_uid, scope or settings.scope, settings.build_config(), instanced)
