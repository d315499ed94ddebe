"""`bvhlab.build` and the `Bvh` it returns: a thin, checked layer over the C++ core (what a build is
asked for: `build_config.BuildConfig`)."""

from __future__ import annotations

import copy
import threading
import weakref
from collections.abc import Callable
from typing import TYPE_CHECKING

import numpy as np

from . import _checks, _core
from ._mesh_changes import checked_change
from .build_config import BuildConfig
from .inspect.node_data import NodeData
from .ray_query import run_occluded_query, run_ray_query

if TYPE_CHECKING:
    from .instanced import InstancedBvh
    from .optimize import OptimizeConfig, OptimizeStats
    from .update import UpdateConfig, UpdateStats

#: The deepest a tree may be: the traversals' fixed stack (shaders/gpu_types.h).
MAX_TREE_HEIGHT = _core.MAX_TREE_HEIGHT
#: Supported ray directions and sphere radii (core_cpp/include/bvhlab/coordinate_range.h); the
#: coordinates' limit is `bvhlab.scene.MAX_COORDINATE`.
MIN_DIRECTION, MAX_DIRECTION = float(_core.MIN_DIRECTION), float(_core.MAX_DIRECTION)
MIN_RADIUS = float(_core.MIN_RADIUS)

#: One flattened node, 32 bytes (shaders/gpu_types.h): for a leaf `index` is the first slot in
#: `Bvh.refs` and `info` the primitive count; for an internal node `index` is the second child
#: (the first is the next node) and `info` is NODE_INTERNAL_BIT | skip index.
NODE_DTYPE = np.dtype([("lo", "<f4", (3,)), ("index", "<u4"), ("hi", "<f4", (3,)), ("info", "<u4")])
NODE_INTERNAL_BIT = _core.NODE_INTERNAL_BIT
REF_SPHERE_BIT = _core.REF_SPHERE_BIT


def build(
    scene_or_triangles,
    spheres: np.ndarray | None = None,
    *,
    config: BuildConfig | None = None,
    progress: Callable[[float], bool | None] | None = None,
    **settings,
) -> Bvh | InstancedBvh:
    """Build a BVH over triangles (float32 (T,3,3)) and spheres (float32 (S,4): centre, radius).

    `scene_or_triangles` is a `bvhlab.Scene` or a triangle array. The settings are a BuildConfig
    (`config`, default BuildConfig()), with any of its fields given by name on top
    (`build(scene, method="median")`):
    `method` is one of METHODS, `axis` one of AXES ("auto": all three axes for the SAH methods,
    the largest centroid extent for the others; "lbvh" and "sbvh", which split on all three axes
    their own way, ignore it); `bins` (MIN_BINS..MAX_BINS) is used by the binned methods
    (BINNED_METHODS: "sah" and "sbvh"), whose equal buckets divide the node's box
    (`bin_bounds="box"`) or its centroid bounds ("centroids", the report's §2.3.2); leaves hold at
    most `max_leaf_size` primitives, and the SAH methods may stop earlier when a leaf is cheaper.
    `sah_block` (a power of two up to MAX_SAH_BLOCK) makes the SAH count primitives in whole blocks
    of that many above a node of one block, as the wide CPU traversal tests four triangles at once
    (Embree's sahBlockSize); 1 is the report's SAH. The defaults give a fast tree for little build
    time; the report's Table 1 settings are method="sah", bins=12, bin_bounds="centroids",
    axis="largest", max_leaf_size=1, sah_block=1. `threads` = 0 uses every core; the tree never depends on it.
    Bad input raises TypeError or ValueError; a vertex or sphere outside ±MAX_COORDINATE (2^40 ≈
    1.1e12, where float32 ray tests would overflow), a sphere radius below MIN_RADIUS (2^-60,
    where its square underflows) and triangles in a scene less than 2^-32 (2.3e-10) units across
    (where the triangle test's products underflow) are bad input.

    `progress(fraction)` is called on this thread now and then, last with 1.0; its result is taken
    by its truth value (None means go on), and a false one cancels the build (BuildCancelled),
    even at 1.0. What the callable raises is raised again, as itself, once the build has stopped.
    Ctrl-C stops a build promptly (KeyboardInterrupt), with or without `progress`.

    A Scene with instances (`Scene.is_instanced`) gets a two-level tree, a `bvhlab.InstancedBvh`:
    one tree per mesh with these settings, shared by its instances, and a TLAS over the instances.
    """
    from .scene import Scene  # local import: scene imports this module

    instanced = False
    if isinstance(scene_or_triangles, Scene):
        if spheres is not None:
            raise ValueError("pass spheres inside the Scene, not beside it")
        triangles, spheres = scene_or_triangles.triangles, scene_or_triangles.spheres
        instanced = scene_or_triangles.is_instanced
    else:
        triangles = scene_or_triangles
    triangles = _checks.float32_array("triangles", triangles, (3, 3))
    if spheres is not None:
        spheres = _checks.float32_array("spheres", spheres, (4,))
    if config is None:
        config = BuildConfig()
    elif not isinstance(config, BuildConfig):
        raise TypeError(f"config must be a bvhlab.BuildConfig, got {type(config).__name__}")
    if settings:
        config = config.replace(**settings)
    if progress is not None and not callable(progress):
        raise TypeError("progress must be callable (fraction -> bool) or None")
    if instanced:
        from .instanced import build_instanced

        return build_instanced(scene_or_triangles, config, progress)
    return Bvh(_core.build(triangles, spheres, config.core(), progress), config)


class Bvh:
    """A built tree. Arrays returned by its properties are read-only views of the C++ data.

    A Bvh may be shared between threads: `intersect`, `boxes` and the arrays read one version of
    the tree; `refit` publishes a new version, so a reader sees the old tree or the new one."""

    _source: Bvh  #: the tree a snapshot is of (_snapshot; a tree itself has none)
    _of_instances = False  #: a TLAS (InstancedBvh.tlas): its references are instances

    def __init__(self, core: _core.Bvh, config: BuildConfig):
        self._core = core
        self.config = config
        self._stats: tuple[int, dict] | None = None  # (revision, stats)
        self._node_data: tuple[int, NodeData] | None = None  # (revision, data)
        self._node_structure: tuple[int, NodeData] | None = None  # (revision, data without EPO)
        # the InstancedBvhs this tree is a mesh of (_mesh_changes): a change through `meshes[k]`
        # must leave their instances in the coordinate range
        self._placed_by: weakref.WeakSet[InstancedBvh] = weakref.WeakSet()
        # a checked change and its undoing, one at a time: an undo put back the version before
        # its own change, over another thread's change made meanwhile (re-entrant: the core
        # refuses a change from within one, ReentrantCall, rather than this lock waiting on itself)
        self._changing = threading.RLock()

    def _snapshot(self) -> Bvh:
        """This tree's current version, for a reading in several steps (a pick's boxes and its hit,
        a pixel's render scene and record) while another thread may refit or update it: the core's
        copy-on-write fork, which keeps the version; `_source` names the tree it is of (what the
        inspection's caches key by, as InstancedBvh.snapshot's), whose node data of the same
        version it shares (node_data). Never refit: its revision numbers are its tree's."""
        view = Bvh(self._core.fork(), self.config)
        view._source = getattr(self, "_source", self)  # not set on a tree itself: no cycle to collect
        return view

    def __repr__(self) -> str:
        s = self.stats
        # a TLAS (InstancedBvh.tlas) holds no geometry: its references are instances
        held = f"{s['references']} instances" if self._of_instances else f"{s['primitives']} primitives"
        return f"<bvhlab.Bvh {s['method']} {held}, {s['nodes']} nodes, height {s['height']}, SAH {s['sah_cost']:.2f}>"

    # -- numbers ---------------------------------------------------------------------------
    @property
    def stats(self) -> dict:
        """primitives, triangles, spheres, references (leaf slots: more than the primitives in an
        SBVH, whose references repeat), nodes, leaves, height (largest leaf depth + 1, root depth 0),
        sah_cost (Σ_internal A/A_root + Σ_leaf A/A_root·N), build_ms, avg_leaf_size, max_leaf_size,
        nodes_per_depth, leaves_per_depth, leaf_size_histogram ([k] = leaves with k primitives),
        memory_bytes, and the build settings (bins and bin_bounds None where the method does not
        bin: BINNED_METHODS)."""
        cached = self._stats
        revision = self._core.revision
        if cached is None or cached[0] != revision:
            stats = self._core.stats()
            stats["threads"] = self.config.threads
            if self._core.revision != revision:  # a refit or update on another thread meanwhile
                return stats  # of one version or the other: not kept, it may be the old one
            cached = self._stats = (revision, stats)
        return copy.deepcopy(cached[1])  # its lists too: an edit of one returned changed the next

    def node_data(self, *, threads: int = 0, epo: bool = True) -> NodeData:
        """Every node's box, depth, parent, children, primitives under it, area, SAH term and its
        subtree's share of the SAH cost, child overlap and end-point overlap (EPO), as arrays made
        in C++ for all nodes at once (bvhlab.inspect.node_data.NodeData). Made once per revision.
        Without `epo` the EPO terms are NaN (`NodeData.has_epo`), and EPO is most of the time
        (a 1M-triangle knot: 1.44 s, 0.17 s without it); the whole data, where made already,
        serves both."""
        threads = _checks.integer("threads", threads, 0, 4096)
        epo = _checks.flag("epo", epo)
        whole = self._own_node_data("_node_data")
        if whole is not None:
            return whole
        if epo:
            return self._make_node_data("_node_data", threads, True)
        rest = self._own_node_data("_node_structure")  # (a tree of no nodes is a NodeData of length 0)
        return rest if rest is not None else self._make_node_data("_node_structure", threads, False)

    def _own_node_data(self, slot: str) -> NodeData | None:
        """This revision's node data in `slot`, this tree's or (a snapshot) its source's, or None:
        a snapshot (_snapshot) and its tree share a version's node data both ways (a pick on a
        snapshot made them again at every click: 0.17 → 0.8 s a pick, 500K triangles)."""
        revision = self._core.revision
        for holder in (self, getattr(self, "_source", None)):
            cached = getattr(holder, slot, None) if holder is not None else None
            if cached is not None and cached[0] == revision:
                setattr(self, slot, cached)
                return cached[1]
        return None

    def _make_node_data(self, slot: str, threads: int, epo: bool) -> NodeData:
        d = self._core.node_data(threads, epo)  # of one version, whatever a refit does meanwhile
        made = (d["revision"], NodeData.from_core(d))
        setattr(self, slot, made)
        source = getattr(self, "_source", None)
        if source is not None and source._core.revision == d["revision"]:
            setattr(source, slot, made)
        return made[1]

    def cached_node_data(self) -> NodeData | None:
        """The node data `node_data()` made for this revision of the tree, or None (never computes:
        for a panel that must not block Blender while it draws)."""
        cached = self._node_data
        return cached[1] if cached is not None and cached[0] == self._core.revision else None

    @property
    def revision(self) -> int:
        """0 when built; each refit, update and optimisation that changes the tree publishes a new
        version of it and adds 1 (a refused one adds none). Arrays taken from an older version stay
        valid (and unchanged)."""
        return self._core.revision

    # -- the tree as arrays ------------------------------------------------------------------
    @property
    def nodes(self) -> np.ndarray:
        """Structured view (NODE_DTYPE) of the flattened depth-first nodes, zero-copy."""
        return _readonly(self._core.nodes_bytes().view(NODE_DTYPE).reshape(-1))

    @property
    def refs(self) -> np.ndarray:
        """uint32 primitive references in leaf order; REF_SPHERE_BIT marks a sphere."""
        return _readonly(self._core.refs())

    @property
    def depths(self) -> np.ndarray:
        """uint8 depth of each node (root 0)."""
        return _readonly(self._core.depths())

    @property
    def is_leaf(self) -> np.ndarray:
        return (self.nodes["info"] & NODE_INTERNAL_BIT) == 0

    @property
    def skip(self) -> np.ndarray:
        """Skip (miss) index of each node: the first node after its subtree."""
        info = self.nodes["info"]
        leaf = (info & NODE_INTERNAL_BIT) == 0
        return np.where(leaf, np.arange(len(info), dtype=np.uint32) + 1, info & ~np.uint32(NODE_INTERNAL_BIT))

    def boxes(self, depth_min: int = 0, depth_max: int | None = None, *, leaves_only: bool = False):
        """Boxes of the nodes whose depth d satisfies depth_min <= d <= depth_max (only the leaves
        with `leaves_only`), sorted by depth (depth-first order within a depth; report §3.3.1).
        Returns new arrays (lo (K,3) float32, hi (K,3) float32, depth (K,) uint8); a range past
        the tree's height gives none; a depth_min above depth_max raises ValueError."""
        return self._core.boxes(*_checks.depth_range(depth_min, depth_max), bool(leaves_only))

    # -- queries -----------------------------------------------------------------------------
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
        """Closest hits of rays origin + t·direction, t in (tmin, tmax), on every core.

        Origins lie within ±MAX_COORDINATE (2^40) and the largest component of each direction in
        [2^-80, 2^80]; directions need not be normalised (each ray is scaled by a power of two for
        the arithmetic, exactly, so t is in units of the given direction); `tmin` and `tmax` are
        numbers >= 0 (tmax inf: no limit). Anything else raises ValueError naming the ray. Ctrl-C
        stops a long batch (KeyboardInterrupt).

        `traversal`: "stack" (binary tree, nearer child first), "stackless" (skip indices,
        report §3.1), or "wide" (an 8-wide copy of the tree made on first use; the fastest).
        All three return the same hits.

        Returns a dict of arrays: t (inf on a miss), prim (index within its kind, -1 on a miss),
        kind (0 triangle, 1 sphere), u, v (triangle barycentrics; sphere longitude/2π, colatitude/π),
        and with `nodes_visited=True` nodes_visited (for heatmaps: the binary walks' box tests; the
        wide walk's wide nodes, each eight child boxes tested at once). Counting keeps each
        ray on its own walk: without it, the wide traversal takes a camera's neighbouring rays
        through the tree eight at a time (the same hits, faster)."""
        return run_ray_query(self._core, origins, directions, tmin, tmax, traversal, threads, nodes_visited)

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
        """Any-hit query (shadow rays): for each ray, whether anything lies on it at t in
        (tmin, tmax). The walk of `intersect` that ends at the first hit it finds (Embree's
        rtcOccluded1, tinybvh's IsOccluded), so it answers exactly `intersect(...)["t"] < tmax`
        on every traversal; a hit at exactly tmax does not count, as in `intersect`.

        `tmax`: a number >= 0 (inf: the whole ray), or a float32 array with one per ray. Rays,
        tmin, traversal and threads as for `intersect`; a NaN or negative tmin or tmax raises
        ValueError.
        Returns a bool array, one per ray."""
        return run_occluded_query(self._core, origins, directions, tmin, tmax, traversal, threads)

    def save(self, path) -> None:
        """Writes the tree to `path` (a name ending in .bvhtree, as a whole or not at all): its nodes and
        references, the geometry's fingerprint and the build settings (bvhlab.inspect.tree_file);
        `bvhlab.load_bvh(path, scene)` reads it back over the same geometry."""
        from .inspect.tree_file import save_bvh

        save_bvh(self, path)

    def trace_ray(self, origin, direction, *, tmin: float = 0.0, tmax: float = np.inf, traversal: str = "stack"):
        """What `intersect` does for one ray, step by step (bvhlab.inspect.ray_record.RayRecord):
        the boxes it tested in order and whether each was hit, the primitives it tested, and the
        leaf and primitive of the closest hit. Recorded by the same traversal code ("stack",
        "stackless" or "wide", whose wide nodes and leaves are named by the binary nodes they
        stand for), so its `nodes_visited` is what `intersect` reports for the ray."""
        from .inspect.ray_record import record

        return record(self._core, origin, direction, tmin, tmax, traversal)

    def update(
        self, triangles: np.ndarray, spheres: np.ndarray | None = None, config: UpdateConfig | None = None, **changes
    ) -> UpdateStats:
        """Update the tree for moved geometry (same counts) as `config` says (an UpdateConfig,
        default adaptive, with any of its fields given by name on top: `update(tris, policy="partial")`).
        Publishes a new version of the tree, as refit does, and returns what ran (UpdateStats).
        Costs are compared with the nodes' costs when they were built (this tree as built, or as
        the last rebuild of each subtree left it). A tree with spheres needs them given (an empty
        (0, 4) array removes them, where the policy allows other counts)."""
        from .update import UpdateStats, update_config

        triangles = _checks.float32_array("triangles", triangles, (3, 3))
        if spheres is not None:  # None on a tree with spheres raises ValueError (the core checks)
            spheres = _checks.float32_array("spheres", spheres, (4,))
        core_config = update_config(config, changes).core()
        stats = checked_change(self, lambda core: _core.update_bvh(core, triangles, spheres, core_config))
        return UpdateStats(**stats)

    def optimize(
        self,
        config: OptimizeConfig | None = None,
        *,
        progress: Callable[[float], bool | None] | None = None,
        **changes,
    ) -> OptimizeStats:
        """Restructure the tree to lower its SAH cost by reinsertion (Bittner, Hapala and Havran
        2013), as `config` says (an OptimizeConfig, with any of its fields given by name on top:
        `optimize(iterations=20, time_budget_ms=50)`). Leaves move whole (sizes kept) and no
        geometry is needed. Publishes a new version of the tree, as refit does, never of a higher
        SAH cost, the same whatever the number of threads; returns what it did (OptimizeStats).
        A mesh of an InstancedBvh is optimised holding its InstancedBvhs' locks (checked as
        `refit` is): a `progress` callable must not wait on another thread using them.
        `progress(fraction)` (of the iteration bound, or of the time budget where that is further;
        1.0 once done) and Ctrl-C stop it as they stop a build (BuildCancelled, or what the callable
        raised), the tree left as it was."""
        from .optimize import OptimizeConfig, OptimizeStats

        if config is None:
            config = OptimizeConfig()
        elif not isinstance(config, OptimizeConfig):
            raise TypeError(f"config must be a bvhlab.OptimizeConfig, got {type(config).__name__}")
        if changes:
            config = config.replace(**changes)
        if progress is not None and not callable(progress):
            raise TypeError("progress must be callable (fraction -> bool) or None")
        core_config = config.core()
        stats = checked_change(self, lambda core: _core.optimize_bvh(core, core_config, progress))
        return OptimizeStats(**stats)

    def refit(self, triangles: np.ndarray, spheres: np.ndarray | None = None) -> None:
        """Move the geometry (same counts) and recompute every box, keeping the topology. An SBVH
        (method "sbvh") is rebuilt with its settings instead: its leaf boxes hold clipped parts of
        triangles, which a refit cannot clip again. A mesh of an InstancedBvh (`meshes[k]`) whose
        new geometry an instance would place outside the coordinate range: ValueError, the tree
        as it was (and its revision), as for `update` and `optimize`."""
        triangles = _checks.float32_array("triangles", triangles, (3, 3))
        if spheres is not None:
            spheres = _checks.float32_array("spheres", spheres, (4,))
        checked_change(self, lambda core: core.refit(triangles, spheres))


def _readonly(a: np.ndarray) -> np.ndarray:
    a = a.view()
    a.flags.writeable = False
    return a
