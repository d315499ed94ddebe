"""Two-level trees (issue 34): `InstancedBvh`, a bottom-level tree (a `Bvh`) per mesh of a
`Scene`, shared by every instance of it, and a top-level tree over the instances (C++
core_cpp/include/bvhlab/tlas.h). `bvhlab.build` makes one for a scene with instances."""

from __future__ import annotations

import copy
import threading
from collections.abc import Callable

import numpy as np

from . import _checks, _core
from ._mesh_changes import placing
from .build_config import BuildConfig
from .bvh import Bvh
from .inspect.node_data import NodeData
from .inspect.two_level_data import TwoLevelNodeData
from .ray_query import run_occluded_query, run_ray_query
from .two_level_stats import instanced_stats
from .update import UpdateStats, update_config


class InstancedBvh:
    """A TLAS over a scene's instances and the trees of its meshes (`meshes[k]` for mesh k).

    `intersect` walks both levels: rays are moved into each instance's space, t stays in world
    units, and every hit names its instance and its primitive within the instance's mesh.
    `place` rebuilds only the TLAS, for instances that moved (the meshes' trees are kept);
    `update_mesh` updates one mesh's tree and then the TLAS."""

    #: On a snapshot: the tree it is a view of (what caches of a tree's render scene key by).
    _source: InstancedBvh

    def __init__(self, meshes: list[Bvh], mesh_of: np.ndarray, transforms: np.ndarray, config: BuildConfig):
        self.config = config
        # (TLAS core, mesh index, transforms, meshes, their revisions) as one attribute: place() and
        # update_mesh() on another thread swap it whole, so no reader sees a new TLAS with the old
        # instances or meshes (stats keyed by the one, made of the other, were kept; figures and
        # boxes read in several steps mixed two TLASes); snapshot() holds one for helpers that read
        # in several steps
        self._frozen = False
        self._lock = threading.RLock()  # writers (place, update_mesh, a TLAS made again) one at a time
        self._stats: tuple | None = None  # (what they were made of, stats)
        self._tlas: tuple | None = None  # (the core TLAS, it as a Bvh)
        self._tlas_data: tuple | None = None  # (the TLAS it was made of, NodeData, leaf_first, refs)
        self._analysed: tuple | None = None  # (_analysis_key(), TwoLevelNodeData)
        trees = _checked_meshes(meshes)
        if not isinstance(config, BuildConfig):
            raise TypeError(f"config must be a bvhlab.BuildConfig, got {type(config).__name__}")
        # its meshes told before its TLAS is made, under its lock (a change of one meanwhile went
        # unchecked: the review); refused, it places nothing (one told the trees before a bad
        # argument broke their changes while its error was kept: an audit)
        with self._lock:
            self._state: tuple = (None, None, None, trees, None)
            try:
                placing(self, trees)
                self._state = _make_state(trees, mesh_of, transforms, config.threads)
            except BaseException:
                self._state = (None, None, None, (), ())
                raise

    def _check_placement(self, tree: Bvh, version: _core.Bvh) -> None:
        """ValueError where this tree's next TLAS would refuse an instance of `tree` were it at
        `version` (a fork of it changed: _mesh_changes)."""
        _, mesh_of, transforms, meshes, _ = self._state
        for k in (k for k, m in enumerate(meshes) if m is tree):
            if k and version.primitive_counts[1]:  # Bvh.update with spheres, which update_mesh refuses
                raise _spheres_beyond_mesh_0(k)
            of_k = np.flatnonzero(mesh_of == k).astype(np.uint32)
            _core.check_placement(version, k, of_k, np.ascontiguousarray(transforms[of_k]))

    def _places(self, tree: Bvh) -> bool:
        """Whether `tree` is one of the meshes this places now (_mesh_changes; a snapshot, which
        places nothing new, is in no mesh's `_placed_by`)."""
        return any(m is tree for m in self._state[3])

    @property
    def meshes(self) -> tuple[Bvh, ...]:
        """The meshes' trees, mesh k's at k (a tuple: `update_mesh` replaces one). A tree updated
        through it (`meshes[k].update(...)`) is followed: the next query, render or figure makes
        the TLAS again over it (it kept answering for the old geometry). Such a change that an
        instance would place outside the coordinate range is refused (ValueError) and undone."""
        return self._current()[3]

    def snapshot(self) -> InstancedBvh:
        """This tree as it is now, for reading in several steps (figures, boxes, picks) while
        another thread may call `place` or `update_mesh` on it: its own TLAS and meshes stay
        (update_mesh makes a new tree object for the mesh; a mesh tree updated by its caller
        through `meshes[k]` is the one exception: that object is shared)."""
        state = self._current()
        view = object.__new__(InstancedBvh)
        view.__dict__.update(self.__dict__)
        view._state, view._frozen, view._lock = state, True, threading.RLock()
        view._source = getattr(self, "_source", self)  # the tree it is a view of (what caches key by)
        return view

    def _current(self) -> tuple:
        """The state, made again first where a mesh's tree changed since its TLAS was made."""
        state = self._state
        if self._frozen or all(m.revision == r for m, r in zip(state[3], state[4])):
            return state
        with self._lock:
            state = self._state
            if not all(m.revision == r for m, r in zip(state[3], state[4])):
                state = self._state = _make_state(state[3], state[1], state[2], self.config.threads)
        return state

    @property
    def _core(self) -> _core.TwoLevel:
        return self._current()[0]

    @property
    def _placed(self) -> tuple[np.ndarray, np.ndarray]:
        state = self._current()
        return state[1], state[2]

    def __repr__(self) -> str:
        s = self.stats
        return f"<bvhlab.InstancedBvh {s['instances']} instances of {s['meshes']} meshes, TLAS {s['tlas_nodes']} nodes>"

    @property
    def stats(self) -> dict:
        """instances, meshes, tlas_nodes, tlas_height, tlas_sah_cost, tlas_build_ms, tlas_memory_bytes
        (the TLAS and the instance records: what instancing adds over the meshes' trees), and
        meshes_memory_bytes (the meshes' trees, each counted once); and the whole tree's
        (two_level_stats.instanced_stats): primitives and triangles stored (each mesh once) and
        flattened (once per instance), nodes, height, memory_bytes, sah_cost (two-level), per-mesh
        lists (mesh_primitives, mesh_instances, mesh_sah_cost, ...) and the meshes' build method."""
        core, mesh_of, _, meshes, _ = self._current()
        key = _version_key(core, meshes)
        made = self._stats
        if made is None or made[0] != key:
            lo, hi = core.world_boxes()
            made = self._stats = (key, instanced_stats(core.stats(), list(meshes), mesh_of, lo, hi))
        return copy.deepcopy(made[1])  # its lists too: an edit of one returned changed the next

    @property
    def tlas(self) -> Bvh:
        """The TLAS as a Bvh (a copy, made once per TLAS): its node boxes are in world space, its
        references are instance indices (one per leaf), it holds no geometry; its `config` is the
        meshes' (the TLAS is built with the core's default_tlas_config)."""
        core, made = self._core, self._tlas
        if made is None or made[0] is not core:
            tlas = Bvh(core.tlas_tree(), self.config)
            tlas._of_instances = True  # its references are instances, also where there are none
            made = self._tlas = (core, tlas)
        return made[1]

    @property
    def instances(self) -> tuple[np.ndarray, np.ndarray]:
        """(mesh index (N,), object-to-world float32 (N,3,4)) of the instances the TLAS is over."""
        return self._placed

    def tlas_boxes(self, depth_min: int = 0, depth_max: int | None = None, *, leaves_only: bool = False):
        """The TLAS's node boxes (world space) in the depth range, as `Bvh.boxes` gives a tree's:
        (lo (K,3) float32, hi (K,3) float32, depth (K,) uint8), by depth; its leaves are the
        instances' world boxes."""
        return self._core.tlas_boxes(*_checks.depth_range(depth_min, depth_max), bool(leaves_only))

    def tlas_node_data(self) -> NodeData:
        """The TLAS's node data (`Bvh.node_data`'s figures over its nodes, whose primitives are
        instances; EPO 0: it holds no geometry), made once per TLAS."""
        return self._tlas_nodes()[1]

    def tlas_leaf_instances(self, node: int) -> np.ndarray:
        """The instances TLAS leaf `node` holds (none for an inner node)."""
        _, data, leaf_first, refs = self._tlas_nodes()
        if not len(leaf_first):
            raise ValueError("the tree has no instances: its TLAS has no nodes")
        node = _checks.integer("node", node, 0, len(leaf_first) - 1)  # -1 would be the last node
        first = int(leaf_first[node])
        return refs[first : first + int(data.prim_count[node])] if first >= 0 else refs[:0]

    def tlas_leaf_of(self, instance: int) -> int:
        """The TLAS leaf holding `instance` (-1 for an instance of an empty mesh, which no leaf holds)."""
        leaves = self.tlas_leaves_of_instances()
        if not len(leaves):
            raise ValueError("the tree has no instances")
        return int(leaves[_checks.integer("instance", instance, 0, len(leaves) - 1)])  # -1: not the last one

    def tlas_leaves_of_instances(self) -> np.ndarray:
        """(N,) int64: the TLAS leaf holding each instance (-1 for an empty mesh's instance)."""
        core, mesh_of, *_ = self._current()
        _, data, leaf_first, refs = self._tlas_nodes(core)
        out = np.full(len(mesh_of), -1, np.int64)
        leaves = np.flatnonzero(np.asarray(leaf_first) >= 0)
        counts = data.prim_count[leaves].astype(np.int64)
        slots = np.repeat(leaf_first[leaves].astype(np.int64), counts) + (
            np.arange(counts.sum()) - np.repeat(np.cumsum(counts) - counts, counts)
        )
        out[refs[slots]] = np.repeat(leaves, counts)
        return out

    def node_data(self) -> TwoLevelNodeData:
        """The figures of the tree the TLAS and the meshes' trees make together
        (bvhlab.inspect.two_level_data): each mesh tree analysed once (`Bvh.node_data`)."""
        view = self.snapshot()  # one TLAS and one set of meshes throughout
        key = view._analysis_key()
        analysed = self._analysed
        if analysed is None or analysed[0] != key:
            analysed = self._analysed = (key, TwoLevelNodeData.of(view))
        return analysed[1]

    def cached_node_data(self) -> TwoLevelNodeData | None:
        """What `node_data()` made for the current TLAS and meshes, or None (never computes)."""
        state = self._state  # as it is: a mesh updated through meshes[k] is not analysed here
        if not all(m.revision == r for m, r in zip(state[3], state[4])):
            return None
        analysed = self._analysed
        if analysed is not None and analysed[0] == _version_key(state[0], state[3]):
            return analysed[1]
        if all(m.cached_node_data() is not None for m in state[3]):
            return self.node_data()  # only the joining arrays are left to make (milliseconds)
        return None

    def _analysis_key(self) -> tuple:
        state = self._current()
        return _version_key(state[0], state[3])

    def _tlas_nodes(self, core=None) -> tuple:
        core = core or self._core
        made = self._tlas_data
        if made is None or made[0] is not core:
            d = core.tlas_node_data()
            made = self._tlas_data = (core, NodeData.from_core(d), d["leaf_first"], d["refs"])
        return made

    def place(self, mesh_of: np.ndarray, transforms: np.ndarray) -> None:
        """Move the instances (or change them): a new TLAS over the same meshes' trees."""
        self._writable()
        with self._lock:  # after a writer before it (update_mesh's new mesh is kept)
            self._state = _make_state(self._state[3], mesh_of, transforms, self.config.threads)

    def _writable(self) -> None:
        if self._frozen:
            raise RuntimeError("a snapshot of an InstancedBvh is read-only: place or update the tree it was taken of")

    def update_mesh(
        self, k: int, triangles: np.ndarray, spheres: np.ndarray | None = None, config=None, **changes
    ) -> UpdateStats:
        """Mesh k moved or changed: with the same counts its tree is updated as `Bvh.update` does
        (`config`/`changes`: an UpdateConfig, checked whatever the counts), with other counts it
        is rebuilt; the other meshes' trees are not touched. Then the TLAS is made again over the
        same instances (their world boxes follow the mesh). Returns what ran on mesh k. Spheres
        only for mesh 0, as a Scene has them (ValueError for another)."""
        self._writable()
        with self._lock:  # writers one at a time: a second update_mesh kept the first one's mesh out
            return self._update_mesh(k, triangles, spheres, config, **changes)

    def _update_mesh(self, k, triangles, spheres, config, **changes) -> UpdateStats:
        meshes = self._state[3]
        k = _checks.integer("mesh", k, 0, len(meshes) - 1)
        triangles = _checks.float32_array("triangles", triangles, (3, 3))
        config = update_config(config, changes)  # checked (as it is made) also where the counts change
        # the counts alone: the stats (a pass over every node) cost a 1M-triangle mesh 43 ms a frame
        old_triangles, old_spheres = meshes[k]._core.primitive_counts
        if spheres is None and old_spheres:  # as Bvh.update: removing them must be asked for
            raise ValueError(f"mesh {k} has {old_spheres} spheres: pass them (or an empty (0, 4) array to remove them)")
        if spheres is not None:
            spheres = _checks.float32_array("spheres", spheres, (4,))
        n_spheres = 0 if spheres is None else len(spheres)
        if k and n_spheres:  # a tree no Scene describes: its renders refused the scene as another's
            raise _spheres_beyond_mesh_0(k)
        if len(triangles) == old_triangles and n_spheres == old_spheres:
            # a new tree object from the current version (copy-on-write): a snapshot taken before
            # keeps the mesh tree its TLAS was made over
            tree = Bvh(meshes[k]._core.fork(), meshes[k].config)
            stats = tree.update(triangles, spheres, config)
        else:  # another count: a new tree for this mesh alone
            tree = Bvh(_core.build(triangles, spheres, self.config.core(), None), self.config)
            s = tree.stats
            stats = UpdateStats("rebuild", s["build_ms"], s["sah_cost"], 1, s["primitives"])
        meshes = meshes[:k] + (tree,) + meshes[k + 1 :]
        # the new mesh and the TLAS over it in one swap
        try:
            self._state = _make_state(meshes, self._state[1], self._state[2], self.config.threads)
        except ValueError as e:  # the instances did not change: mesh k's new geometry did
            raise ValueError(f"mesh {k}'s new geometry refused, the tree kept as it was: {e}") from None
        placing(self, (tree,))
        return stats

    def world_boxes(self) -> tuple[np.ndarray, np.ndarray]:
        """(lo (N,3), hi (N,3)): each instance's world box, which the TLAS is built over."""
        return self._core.world_boxes()

    def intersect(
        self,
        origins: np.ndarray,
        directions: np.ndarray,
        *,
        tmin: float = 0.0,
        tmax: float = np.inf,
        traversal: str = "wide",
        threads: int = 0,
        nodes_visited: bool = False,
    ) -> dict:
        """As `Bvh.intersect`, through both levels; the dict also holds `instance` (int32, -1 on a
        miss), and `prim` indexes the triangles (or spheres) of that instance's mesh."""
        return run_ray_query(
            self._core, origins, directions, tmin, tmax, traversal, threads, nodes_visited, {"instance": np.int32}
        )

    def trace_ray(self, origin, direction, *, tmin: float = 0.0, tmax: float = np.inf, traversal: str = "stack"):
        """What `intersect` does for one ray through both levels, step by step
        (bvhlab.inspect.ray_record.InstancedRayRecord): the TLAS's box tests, and for each instance
        entered its walk through its mesh's tree (as `Bvh.trace_ray` records it), the closest hit
        with its instance. Recorded by the query's own walk ("stack", "stackless" or "wide" for
        the meshes' trees), so its `nodes_visited` is what `intersect` reports for the ray."""
        from .inspect.ray_record import record_instanced

        return record_instanced(self._core, origin, direction, tmin, tmax, traversal)

    def occluded(
        self,
        origins: np.ndarray,
        directions: np.ndarray,
        tmax: float | np.ndarray = np.inf,
        *,
        tmin: float = 0.0,
        traversal: str = "wide",
        threads: int = 0,
    ) -> np.ndarray:
        """As `Bvh.occluded`, through both levels: the walk ends at the first instance with a hit
        before tmax (exactly `intersect(...)["t"] < tmax`)."""
        return run_occluded_query(self._core, origins, directions, tmin, tmax, traversal, threads)


def _spheres_beyond_mesh_0(k: int) -> ValueError:
    return ValueError(f"mesh {k} cannot hold spheres: only mesh 0 (the scene's own geometry) has them in a Scene")


def _version_key(core: _core.TwoLevel, meshes: list[Bvh]) -> tuple:
    """What cached stats and node data of a two-level tree were made of: the TLAS core itself
    (compared by identity; not its id(), which a freed TLAS's successor may reuse) and each mesh
    tree's object and revision."""
    return (core, tuple(m.revision for m in meshes), tuple(id(m) for m in meshes))


def _make_state(meshes: tuple[Bvh, ...], mesh_of, transforms, threads: int) -> tuple:
    """(TLAS, mesh index int32 (N,), transforms, meshes, the meshes' revisions it was made over):
    InstancedBvh's state, its TLAS with the core's TLAS settings (default_tlas_config) on
    `threads` threads (0: all)."""
    revisions = tuple(m.revision for m in meshes)  # before the TLAS reads them: a later update is seen
    return (*_make_tlas(meshes, mesh_of, transforms, threads), meshes, revisions)


def _make_tlas(meshes, mesh_of, transforms, threads: int) -> tuple:
    """The TLAS with the core's TLAS settings (default_tlas_config) on `threads` threads (0: all),
    and the checked (mesh index int32 (N,), transforms) it was made of."""
    mesh_of = np.asarray(mesh_of)
    if mesh_of.ndim != 1 or not (np.issubdtype(mesh_of.dtype, np.integer) or mesh_of.size == 0):
        raise ValueError(f"mesh indices must be (N,) integers, got shape {mesh_of.shape} dtype {mesh_of.dtype}")
    # all of them before the cast: uint32 would wrap -1 or 2^32 to another mesh
    bad = np.flatnonzero((mesh_of < 0) | (mesh_of >= len(meshes)))
    if len(bad):
        raise ValueError(
            f"instance {bad[0]} refers to mesh {mesh_of[bad[0]]}, but the tree has {len(meshes)} "
            f"mesh{'es' if len(meshes) != 1 else ''}"
        )
    # copies: the caller's arrays (a Scene's) may change in place later, and the tree's placement
    # (InstancedBvh.instances, which a render compares with the scene's) must not change with them
    transforms = np.array(_checks.float32_array("transforms", transforms, (3, 4)), copy=True)
    mesh_of = np.array(mesh_of, np.int32, copy=True)  # as Scene.instances gives them
    core = [m._core for m in meshes]
    config = _core.default_tlas_config()
    config.threads = threads  # the docstring's promise (it was dropped: a TLAS was built on every thread)
    tlas = _core.build_two_level(core, mesh_of.view(np.uint32), transforms, config)
    # handed out as they are (InstancedBvh.instances), so read-only: an edit in place moved an
    # instance the TLAS does not move (a helper's audit: a render then took a scene that is neither)
    mesh_of.setflags(write=False), transforms.setflags(write=False)
    return tlas, mesh_of, transforms


def build_instanced(scene, config: BuildConfig, progress: Callable[[float], bool | None] | None) -> InstancedBvh:
    """The two-level tree of an instanced scene: one build per mesh (with `config`), then the TLAS."""
    mesh_of, transforms = scene.instances()
    n = scene.mesh_count
    trees = []
    for k in range(n):
        part = None if progress is None else (lambda f, k=k: progress((k + f) / n))
        spheres = scene.spheres if k == 0 else None
        core = _core.build(scene.mesh_triangles(k), spheres, config.core(), part)
        trees.append(Bvh(core, config))
    return InstancedBvh(trees, mesh_of, transforms, config)


def _checked_meshes(meshes) -> tuple[Bvh, ...]:
    """`meshes` as a tuple of flat trees (TypeError naming the first that is not one: an ndarray
    or an InstancedBvh was an AttributeError about `_placed_by`)."""
    try:
        trees = tuple(meshes)
    except TypeError:
        raise TypeError(f"meshes must be a sequence of bvhlab.Bvh trees, got {type(meshes).__name__}") from None
    for k, tree in enumerate(trees):
        if not isinstance(tree, Bvh):
            hint = " (two-level trees do not nest)" if isinstance(tree, InstancedBvh) else ""
            raise TypeError(f"meshes[{k}] must be a bvhlab.Bvh (a flat tree), got {type(tree).__name__}{hint}")
    return trees
