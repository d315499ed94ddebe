"""The add-on's one cache of trees (issues 38, 34): the sidebar's Build, its Render, Compare and
Export stats, F12 and the Rendered viewport all take the tree of a (scene, scope, build settings)
from here, so a tree built by one is used by the others (Build, then F12: one build). A scene with
instances (Blender's instancing, exported as meshes and instances) gets a two-level tree
(bvhlab.InstancedBvh) under the same key; a scene without them a Bvh (one identity instance: the
flat tree of before). Each `SceneTree` fits its tree to the geometry it is given one way:

- kept when the arrays are the same (or equal);
- "refit": updated in place with the chosen UpdateConfig (`Bvh.update`: rebuild, refit, partial
  or adaptive) when the primitives are those it was made over, only moved (LiveScene's report);
  in a two-level tree only the meshes whose arrays changed are updated, each with the policy;
- "placed": a new TLAS over the same meshes' trees when only instances moved;
- "built" otherwise (in a two-level tree, only the meshes whose arrays changed are built).

Trees are shared between threads (Blender's UI thread, its render thread, the viewport's worker):
a SceneTree is updated under its own lock, and a Bvh updated in place leaves the versions that
renders in flight hold intact (the core's immutable tree versions), so a reader never needs it."""

from __future__ import annotations

import threading
import time
from collections import OrderedDict
from dataclasses import dataclass, field

import numpy as np

from bvhlab.build_config import BuildConfig

#: Trees kept per scene (the least recently used go first): a user trying a few settings back and
#: forth keeps each; a long comparison does not fill memory.
MAX_TREES_PER_SCENE = 3


@dataclass(frozen=True)
class TreeKey:
    """What a tree depends on besides the geometry: the scene (session_uid), the objects in it
    (scope) and the build settings (BuildConfig compares without `threads`). Whether it is a
    two-level tree follows the geometry (Scene.is_instanced), not the key."""

    scene: int
    scope: str
    config: BuildConfig


@dataclass(frozen=True)
class TreeUpdate:
    """What `SceneTree.update` did: "built", "refit", "placed" (a new TLAS over the same meshes'
    trees) or "kept", how long it took, and the Bvh (or InstancedBvh) that fits the scene it was
    given, as it was then (a view of the SceneTree's: another thread may update that next). `policy`: what the core's
    update ran on the trees updated in place (UpdateStats.policy, several joined by "+"), "" when
    none was; `sah_cost` the tree's after it (two-level for an InstancedBvh); `meshes_built`,
    `meshes_updated`: trees of meshes built and updated in place; `tlas`: a new TLAS was made."""

    action: str
    bvh: object
    ms: float = 0.0
    policy: str = ""
    sah_cost: float = 0.0
    meshes_built: int = 0
    meshes_updated: int = 0
    tlas: bool = False


@dataclass
class Counts:
    """What every SceneTree did (the tests count them): `builds`, updates that built any tree (Build,
    then F12, must build once); `mesh_builds`, `mesh_updates`: trees (a flat scene's, or a mesh's
    BLAS) built and updated in place; `tlas_builds`: TLASes made (moving an instance makes only one)."""

    builds: int = 0
    mesh_builds: int = 0
    mesh_updates: int = 0
    tlas_builds: int = 0
    lock: threading.Lock = field(default_factory=threading.Lock, repr=False, compare=False)

    def add(self, update: TreeUpdate) -> None:
        with self.lock:
            self.builds += update.meshes_built > 0
            self.mesh_builds += update.meshes_built
            self.mesh_updates += update.meshes_updated
            self.tlas_builds += update.tlas

    def snapshot(self) -> tuple[int, int, int, int]:
        """(builds, mesh_builds, mesh_updates, tlas_builds)."""
        with self.lock:
            return self.builds, self.mesh_builds, self.mesh_updates, self.tlas_builds


counts = Counts()


class SceneTree:
    """A Bvh or InstancedBvh over the geometry last given to `update` or `store`, built with `config`."""

    def __init__(self, config: BuildConfig):
        self.config = config
        self.bvh = None
        #: the bvhlab.Scene the tree was last made to fit (update or store): what a pick's rule
        #: for surfaces hidden from camera rays reads beside it, so that a tree updated by the
        #: Rendered viewport (the cache's trees are shared) never goes with another scene
        self.scene = None
        self.lock = threading.Lock()
        self._source: tuple = ([], (None, None))  # [(triangles, spheres) per mesh], (mesh_of, transforms)
        self.generation = 0  # counts the trees it has held (builds, updates, TLASes)
        self.last: TreeUpdate | None = None  # the last update that changed the tree
        self._fresh: tuple[int, float] | None = None  # (generation, SAH cost of a fresh build)

    def update(self, scene, refittable: bool = False, progress=None, threads: int = 0, policy=None) -> TreeUpdate:
        """Make the tree fit `scene` (a bvhlab.Scene). `refittable`: the primitives are those the
        tree was made over, in the same order, only moved (LiveScene's report): trees whose arrays
        changed are then updated in place as `policy` says (a bvhlab.UpdateConfig; default
        adaptive). `progress(fraction)` returning False cancels a build (bvhlab.BuildCancelled).
        `threads`: for a build (0: all)."""
        from bvhlab.update import UpdateConfig

        policy = policy or UpdateConfig()
        with self.lock:
            start = time.perf_counter()
            sources, instances = _sources(scene)
            old_sources, old_instances = self._source
            trees, built, updated, ran = [], 0, [], []
            stats = None  # the last in-place update's UpdateStats
            old_meshes = self._meshes()
            for k, source in enumerate(sources):
                old = old_meshes[k] if k < len(old_meshes) and k < len(old_sources) else None
                if old is not None and _same_arrays(old_sources[k], source):
                    trees.append(old)
                    continue
                stats = (
                    _update_in_place(old, old_sources[k], source, policy) if old is not None and refittable else None
                )
                if stats is None:
                    trees.append(self._build_mesh(source, k, len(sources), progress, threads))
                    built += 1
                    continue
                trees.append(old)
                ran.append(stats.policy)
                if stats.policy == "rebuild":  # adaptive's choice, or the policy asked for
                    built += 1
                else:
                    updated.append(k)
            two_level = scene.is_instanced
            same = len(trees) == len(old_meshes) and not built and not updated
            if same and self.bvh is not None and two_level == _is_instanced(self.bvh):
                if not two_level or _same_arrays(old_instances, instances):
                    self._source, self.scene = (sources, instances), scene
                    return TreeUpdate("kept", _view(self.bvh))
            self._hold(trees, instances, two_level, threads)
            self._source, self.scene = (sources, instances), scene
            action = "built" if built else "refit" if updated else "placed"
            # a flat tree updated in place: the update's own SAH cost (no second pass over the nodes)
            sah = stats.sah_cost if not two_level and stats is not None else self.bvh.stats["sah_cost"]
            update = TreeUpdate(
                action,
                _view(self.bvh),
                (time.perf_counter() - start) * 1e3,
                "+".join(dict.fromkeys(ran)),
                sah,
                built,
                len(updated),
                two_level,
            )
            counts.add(update)
            self.last = update
            return update

    def store(self, bvh, scene) -> None:
        """A tree built elsewhere with this config over `scene` (the sidebar's Build, on its thread)."""
        with self.lock:
            self.bvh, self.scene = bvh, scene
            self._source = _sources(scene)
            self.generation += 1
            meshes = len(self._meshes())
            self.last = TreeUpdate(
                "built", bvh, bvh.stats["build_ms"], "", bvh.stats["sah_cost"], meshes, 0, scene.is_instanced
            )
            counts.add(self.last)

    def fresh_sah_cost(self, threads: int = 0) -> float:
        """The SAH cost a fresh build over the current geometry would have (every mesh's tree built
        again with the tree's settings, then the TLAS): what the updates in place are measured
        against. Computed on demand (it costs a build) and remembered until the tree changes."""
        import bvhlab

        with self.lock:
            if self.bvh is None:
                raise ValueError("no tree yet: build one first")
            if self._fresh is not None and self._fresh[0] == self.generation:
                return self._fresh[1]
            sources, (mesh_of, transforms) = self._source
            config = self.config.replace(threads=threads)
            fresh = [bvhlab.build(t, s, config=config) for t, s in sources]
            if _is_instanced(self.bvh):
                cost = bvhlab.InstancedBvh(fresh, mesh_of, transforms, config).stats["sah_cost"]
            else:
                cost = fresh[0].stats["sah_cost"]
            self._fresh = (self.generation, float(cost))
            return self._fresh[1]

    def known_fresh_sah_cost(self) -> float | None:
        """The fresh build's SAH cost if measured for the current tree (never computes)."""
        fresh = self._fresh
        return fresh[1] if fresh is not None and fresh[0] == self.generation else None

    # -- helpers ---------------------------------------------------------------------------------
    def _meshes(self) -> list:
        if self.bvh is None:
            return []
        return list(self.bvh.meshes) if _is_instanced(self.bvh) else [self.bvh]

    def _build_mesh(self, source: tuple, k: int, n: int, progress, threads: int):
        import bvhlab

        part = None if progress is None else (lambda f: progress((k + f) / n))
        # a cancelled build keeps the tree before (a reader may hold it), and its sources: the next
        # update builds again
        return bvhlab.build(*source, config=self.config.replace(threads=threads), progress=part)

    def _hold(self, trees: list, instances: tuple, two_level: bool, threads: int) -> None:
        import bvhlab

        if two_level:
            self.bvh = bvhlab.InstancedBvh(trees, *instances, self.config.replace(threads=threads))
        else:
            self.bvh = trees[0]
        self.generation += 1


def _view(bvh):
    """The tree as it is now, for the caller to render or read while another thread updates the
    cache's tree in place (the trees are shared: the Rendered viewport's refit between an F12's
    update and its trace failed 19 to 21 of 30 F12s with "the tree was built for other geometry",
    probe): a flat tree's copy-on-write fork, or a two-level tree's snapshot, whose TLAS holds its
    meshes' versions."""
    return bvh.snapshot() if _is_instanced(bvh) else bvh._snapshot()


def _sources(scene) -> tuple[list, tuple]:
    """What a tree over `scene` is made of: (triangles, spheres) of each mesh (spheres: mesh 0's,
    None for the others), and (mesh_of, transforms) of its instances ((None, None): flat)."""
    if not scene.is_instanced:
        return [(scene.triangles, scene.spheres)], (None, None)
    sources = [(scene.mesh_triangles(k), scene.spheres if k == 0 else None) for k in range(scene.mesh_count)]
    return sources, scene.instances()


def _update_in_place(tree, old_source: tuple, source: tuple, policy):
    """Update `tree` for moved primitives (same counts) with `policy` (Bvh.update); None when the
    counts differ (or the core refuses the geometry): the tree must be built."""
    (old_triangles, old_spheres), (triangles, spheres) = old_source, source
    if old_triangles is None or len(old_triangles) != len(triangles):
        return None
    if (old_spheres is None) != (spheres is None) or (spheres is not None and len(old_spheres) != len(spheres)):
        return None
    try:
        return tree.update(triangles, spheres, policy)
    except ValueError:  # not the geometry the tree was built over after all: build instead
        return None


def _same_arrays(a: tuple, b: tuple) -> bool:
    return all(_equal(x, y) for x, y in zip(a, b))


#: Values of an array compared before the whole of it (a moved object usually shows among them).
_SAMPLE = 4096


def _equal(x, y) -> bool:
    """The same array, or equal ones; a sample of the values is compared first, so that geometry
    that moved is told apart without a pass over all of it (the viewport's frames)."""
    if x is y:
        return True
    if x is None or y is None or x.shape != y.shape:
        return False
    step = max(1, x.size // _SAMPLE)
    if not np.array_equal(x.reshape(-1)[::step], y.reshape(-1)[::step]):
        return False
    return bool(np.array_equal(x, y))


def _is_instanced(bvh) -> bool:
    import bvhlab

    return isinstance(bvh, bvhlab.InstancedBvh)


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


def key_of(blender_scene, scope: str | None = None) -> TreeKey:
    """The key of the tree the scene's settings (scene.bvhlab) ask for; `scope`: the objects in it
    when not the settings' (the render engine always renders the visible ones)."""
    settings = blender_scene.bvhlab
    return TreeKey(blender_scene.session_uid, scope or settings.scope, settings.build_config())


def update_config(blender_scene):
    """The UpdateConfig the scene's settings ask for (scene.bvhlab.update_policy)."""
    from bvhlab.update import UpdateConfig

    return UpdateConfig(policy=blender_scene.bvhlab.update_policy)
