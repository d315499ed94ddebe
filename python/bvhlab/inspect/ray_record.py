"""`RayRecord`: what one ray's traversal did, recorded by the traversal code itself
(core_cpp/include/bvhlab/ray_record.h), and `trace_pixel`: the same for a pixel's primary ray,
made by the tracer's own camera code."""

from __future__ import annotations

import threading
import warnings
import weakref
from dataclasses import dataclass, field

import numpy as np

from .. import _checks, _core
from .._render_scene import SceneCache
from ..scene_parts import Rays

#: Traversals that can be recorded: the binary walks and the wide one (`Bvh.intersect`'s default),
#: whose wide nodes and leaves are named by the binary nodes they stand for.
RECORD_TRAVERSALS = ("stack", "stackless", "wide")
#: Traversals of the tracer (RenderOptions.traversal), which trace_pixel records.
PIXEL_TRAVERSALS = ("stack", "stackless")


class _KeptRenderScene:
    """The render scene trace_pixel and the pick's rule for hidden surfaces last used, made again
    only when the scene, its materials or the tree change (SceneCache's key); each call made one,
    about a second for a million triangles, on every pixel asked or box picked. Dropped when the
    tree it was made for is (its owner, a weak reference): the cache's key holds the tree's core,
    which would otherwise stay in memory, with its render scene, until another tree is asked.
    Safe across threads."""

    def __init__(self):
        self._lock = threading.RLock()  # a finalizer may run in a thread holding it (a collection in get)
        self._cache = SceneCache()
        self._owner: weakref.ref | None = None
        self._watched: weakref.WeakSet = weakref.WeakSet()  # trees with a finalizer (one each)

    def get(self, scene, bvh) -> _core.RenderScene:
        owner = getattr(bvh, "_source", bvh)  # a two-level tree's snapshot (InstancedBvh.snapshot) stands for it
        with self._lock:
            if self._owner is None or self._owner() is not owner:
                self._cache, self._owner = SceneCache(), weakref.ref(owner)
                if owner not in self._watched:
                    self._watched.add(owner)
                    weakref.finalize(owner, self._drop, self._owner).atexit = False
            cache = self._cache
        return cache.get(scene, bvh)

    def _drop(self, owner: weakref.ref) -> None:
        with self._lock:
            if self._owner is owner or (self._owner is not None and self._owner() is None):
                self._cache, self._owner = SceneCache(), None


_RENDER_SCENES = _KeptRenderScene()


class HiddenSurfaceWarning(UserWarning):
    """trace_pixel of the wide walk on a scene with surfaces hidden from camera rays: its record
    walks the tree to the closest surface, the tracer passes a hidden one by and goes on (its hit,
    box tests and counters can differ from the record's at the pixels such a surface covers). The
    stack and stackless records pass them by as the tracer does."""


@dataclass(frozen=True)
class RayRecord:
    """Boxes tested in order (`box_nodes`, with `box_hit`: whether the ray entered), primitives
    tested in order (`prim_slots` in the tree's leaf order, `prim_refs` their references with
    REF_SPHERE_BIT for spheres, `prim_leaf` the leaf, `prim_box_test` how many box tests came
    before, `prim_closer` whether it became the closest hit), and the closest hit as
    `Bvh.intersect` returns it (t, prim, kind, u, v) with its slot and leaf (-1 on a miss).
    `nodes_visited` is what `Bvh.intersect` reports for the ray: the box tests (`len(box_nodes)`)
    of the binary walks; for the wide walk the wide nodes visited (`wide_nodes`: the binary node
    each stands for), each testing its children's boxes at once (`box_wide_step`: the position in
    `wide_nodes` of the node each box test belongs to). A wide leaf is a subtree of at most four
    primitives, named by its top binary node (`prim_leaf`, `hit_leaf`)."""

    origin: tuple
    direction: tuple
    tmin: float
    tmax: float
    traversal: str
    box_nodes: np.ndarray
    box_hit: np.ndarray
    prim_slots: np.ndarray
    prim_refs: np.ndarray
    prim_leaf: np.ndarray
    prim_box_test: np.ndarray
    prim_closer: np.ndarray
    t: float
    prim: int
    kind: int
    u: float
    v: float
    hit_slot: int
    hit_leaf: int
    nodes_visited: int = 0
    wide_nodes: np.ndarray = field(default_factory=lambda: np.zeros(0, np.uint32))
    box_wide_step: np.ndarray = field(default_factory=lambda: np.zeros(0, np.uint32))
    pixel: tuple | None = field(default=None)  #: (x, y, sample) for trace_pixel's records

    @property
    def box_tests(self) -> int:
        return len(self.box_nodes)

    @property
    def box_hits(self) -> int:
        return int(self.box_hit.sum())

    @property
    def prim_tests(self) -> int:
        return len(self.prim_slots)

    def steps(self) -> list[dict]:
        """The traversal as one list of steps in order: box tests and primitive tests interleaved."""
        out: list[dict] = []
        prim = 0
        for step in range(self.box_tests + 1):
            while prim < self.prim_tests and self.prim_box_test[prim] == step:
                ref = int(self.prim_refs[prim])
                sphere = bool(ref & _core.REF_SPHERE_BIT)
                out.append(
                    {
                        "step": "prim",
                        "leaf": int(self.prim_leaf[prim]),
                        "slot": int(self.prim_slots[prim]),
                        "kind": "sphere" if sphere else "triangle",
                        "prim": ref & ~_core.REF_SPHERE_BIT if sphere else ref,
                        "closer": bool(self.prim_closer[prim]),
                    }
                )
                prim += 1
            if step < self.box_tests:
                if len(self.box_wide_step) and (step == 0 or self.box_wide_step[step] != self.box_wide_step[step - 1]):
                    out.append({"step": "wide node", "node": int(self.wide_nodes[self.box_wide_step[step]])})
                out.append({"step": "box", "node": int(self.box_nodes[step]), "hit": bool(self.box_hit[step])})
        return out

    def summary(self) -> dict:
        """Counts and the closest hit as plain values (what the CLI prints and writes)."""
        return {
            **_ray_fields(self),
            "box_tests": self.box_tests,
            "box_hits": self.box_hits,
            "prim_tests": self.prim_tests,
            "t": self.t,
            "prim": self.prim,
            "kind": _kind_name(self.kind, self.prim),
            "hit_leaf": self.hit_leaf,
            "hit_slot": self.hit_slot,
        }


def record(
    core_bvh, origin, direction, tmin: float, tmax: float, traversal: str, pixel=None, camera_of=None
) -> RayRecord:
    """The record of one ray through `core_bvh` (a `_core.Bvh`); types checked here, values in C++.
    `camera_of`: a `_core.RenderScene` of the tree whose camera rays the record walks as (the
    primitives they do not see passed by, as the tracer passes them)."""
    origin = _point("origin", origin)
    direction = _point("direction", direction)
    _checks.choice("traversal", traversal, RECORD_TRAVERSALS)
    tmin, tmax = _checks.real("tmin", tmin, 0.0), _checks.real("tmax", tmax, 0.0)
    d = core_bvh.trace_ray(origin, direction, tmin, tmax, traversal, camera_of)
    d.pop("revision")
    return _from_core(d, origin, direction, tmin, tmax, traversal, pixel)


def _from_core(d: dict, origin, direction, tmin, tmax, traversal, pixel=None) -> RayRecord:
    for value in d.values():
        if isinstance(value, np.ndarray):
            value.flags.writeable = False
    return RayRecord(origin, direction, tmin, tmax, traversal, pixel=pixel, **d)


@dataclass(frozen=True)
class InstancedRayRecord:
    """One ray's walk through a two-level tree (`InstancedBvh.trace_ray`): `tlas`, the TLAS walk's
    record (its nodes are the TLAS's; its "primitives" are the instances entered, in order:
    `tlas.prim_refs` the instance, `tlas.prim_leaf` the TLAS leaf, -1 where a scene of one
    identity instance has no TLAS walk, `tlas.prim_closer` whether it held a nearer hit), and
    `blas[j]`, the walk of the j-th instance entered through its mesh's tree (nodes and slots of
    `InstancedBvh.meshes[mesh of that instance]`, t in world units). The closest hit as
    `InstancedBvh.intersect` returns it, with its instance, the mesh tree's leaf (`hit_leaf`) and
    the TLAS leaf (`hit_tlas_leaf`). `nodes_visited` is intersect's figure for the ray: the TLAS's
    box tests plus each instance walk's nodes_visited."""

    origin: tuple
    direction: tuple
    tmin: float
    tmax: float
    traversal: str
    tlas: RayRecord
    blas: tuple
    nodes_visited: int
    instance: int
    hit_tlas_leaf: int
    pixel: tuple | None = field(default=None)

    @property
    def instances(self) -> np.ndarray:
        """The instances entered, in order (one per `blas` record)."""
        return self.tlas.prim_refs

    @property
    def hit(self) -> RayRecord | None:
        """The record of the instance walk that found the closest hit (None on a miss)."""
        if self.instance < 0:
            return None
        closer = np.flatnonzero(self.tlas.prim_closer)
        return self.blas[int(closer[-1])]

    @property
    def t(self) -> float:
        return self.tlas.t

    @property
    def prim(self) -> int:
        return self.tlas.prim

    @property
    def kind(self) -> int:
        return self.tlas.kind

    @property
    def hit_leaf(self) -> int:
        hit = self.hit
        return -1 if hit is None else hit.hit_leaf

    @property
    def hit_slot(self) -> int:
        hit = self.hit
        return -1 if hit is None else hit.hit_slot

    def summary(self) -> dict:
        """Counts and the closest hit as plain values (what the CLI prints and writes)."""
        hit = self.hit
        return {
            **_ray_fields(self),
            "tlas_box_tests": self.tlas.box_tests,
            # through a TLAS leaf: a scene of one identity instance is walked flat, as the tracer
            # walks it (its instance_hits counter is 0 there), though its one walk is recorded
            "instances_entered": int(np.count_nonzero(self.tlas.prim_leaf != _NO_NODE)),
            "box_tests": self.tlas.box_tests + sum(b.box_tests for b in self.blas),
            "box_hits": self.tlas.box_hits + sum(b.box_hits for b in self.blas),
            "prim_tests": sum(b.prim_tests for b in self.blas),
            "t": self.t,
            "prim": self.prim,
            "kind": _kind_name(self.kind, self.prim),
            "instance": self.instance,
            "hit_tlas_leaf": self.hit_tlas_leaf,
            "hit_leaf": -1 if hit is None else hit.hit_leaf,
            "hit_slot": -1 if hit is None else hit.hit_slot,
        }

    def steps(self) -> list[dict]:
        """The walk as one list of steps: the TLAS's box tests, and at each instance entered an
        "instance" step followed by its walk's steps (each with its instance)."""
        out: list[dict] = []
        tlas = self.tlas
        j = 0
        for step in range(tlas.box_tests + 1):
            while j < len(self.blas) and tlas.prim_box_test[j] == step:
                out.append(
                    {
                        "step": "instance",
                        "instance": int(tlas.prim_refs[j]),
                        "leaf": int(tlas.prim_leaf[j]) if tlas.prim_leaf[j] != _NO_NODE else -1,
                        "closer": bool(tlas.prim_closer[j]),
                    }
                )
                out.extend({**s, "instance": int(tlas.prim_refs[j])} for s in self.blas[j].steps())
                j += 1
            if step < tlas.box_tests:
                out.append({"step": "tlas box", "node": int(tlas.box_nodes[step]), "hit": bool(tlas.box_hit[step])})
        return out


_NO_NODE = 0xFFFFFFFF


def record_instanced(
    core_two_level, origin, direction, tmin: float, tmax: float, traversal: str, pixel=None, camera_of=None
):
    """The record of one ray through `core_two_level` (a `_core.TwoLevel`); `camera_of` as record's."""
    origin = _point("origin", origin)
    direction = _point("direction", direction)
    _checks.choice("traversal", traversal, RECORD_TRAVERSALS)
    tmin, tmax = _checks.real("tmin", tmin, 0.0), _checks.real("tmax", tmax, 0.0)
    d = core_two_level.trace_ray(origin, direction, tmin, tmax, traversal, camera_of)
    ray = (origin, direction, tmin, tmax, traversal)
    blas = tuple(_from_core(b, *ray) for b in d["blas"])
    return InstancedRayRecord(
        *ray,
        tlas=_from_core(d["tlas"], *ray),
        blas=blas,
        nodes_visited=int(d["nodes_visited"]),
        instance=int(d["instance"]),
        hit_tlas_leaf=int(d["hit_tlas_leaf"]),
        pixel=pixel,
    )


def trace_pixel(scene, bvh, x: int, y: int, *, width: int, height: int, options=None, camera=None, sample: int = 0):
    """The record of the primary ray of sample `sample` of pixel (x, y) (row 0 at the top) of a
    `width`×`height` render of `scene` with `bvh` (a Bvh, or an InstancedBvh: then an
    InstancedRayRecord): the ray the tracer traces there (its camera code and clipping; the
    overlay's lines are not drawn), walked by the traversal of `options.traversal` (stack or
    stackless: its box tests are the pixel's cost at one sample; wide: each wide node's children,
    where the render's cost counts 8 a wide node, its empty slots too). Surfaces hidden from camera
    rays (Material.hidden_from) are passed by as the tracer passes them: tested, never the hit. The
    wide walk does not pass them by (the tracer's wide walk leaves such a ray to the stack walk): a
    scene with them gets a HiddenSurfaceWarning there, its record walking to the closest surface."""
    from .._render_settings import render_settings
    from ..render_options import options_from

    options = options_from(options, {}).for_backend(cpu=True, counts_shown=True)  # "auto": a record is counts
    hidden = _hidden_from_camera(scene)
    if hidden and options.traversal == "wide":
        warnings.warn(
            "the scene has surfaces hidden from camera rays, which the tracer passes by and the wide walk's "
            "record does not: at the pixels they cover its hit and box tests are the tree's closest surface's "
            "(a stack or stackless record passes them by)",
            HiddenSurfaceWarning,
            stacklevel=2,
        )
    from ..instanced import InstancedBvh

    settings = render_settings(scene, bvh, width, height, options, camera)  # types checked
    # one version for the render scene and the record: a refit or `place` on another thread between
    # them was refused as "the render scene is of another version of the tree" (probe)
    bvh = bvh.snapshot() if isinstance(bvh, InstancedBvh) else bvh._snapshot()
    render_scene = _RENDER_SCENES.get(scene, bvh)
    x = _checks.integer("x", x, 0, 2**32 - 1)
    y = _checks.integer("y", y, 0, 2**32 - 1)
    sample = _checks.integer("sample", sample, 0, 2**32 - 1)
    origin, direction, tmin, tmax = _core.pixel_ray(render_scene, settings, x, y, sample)
    # the core's rule is empty where no material hides (RenderScene.hidden): always asked
    camera_of = render_scene if options.traversal != "wide" else None
    return record_of(bvh, origin, direction, tmin, tmax, options.traversal, pixel=(x, y, sample), camera_of=camera_of)


def record_of(bvh, origin, direction, tmin, tmax, traversal, *, pixel=None, camera_of=None):
    """The record of one ray through `bvh`: a RayRecord for a bvhlab.Bvh, an InstancedRayRecord for
    an InstancedBvh (record, record_instanced)."""
    walk = record_instanced if isinstance(bvh._core, _core.TwoLevel) else record
    return walk(bvh._core, origin, direction, tmin, tmax, traversal, pixel=pixel, camera_of=camera_of)


def camera_rule(scene, bvh):
    """What a record passes by as the tracer's camera rays do (`camera_of`): the render scene of
    `scene` and `bvh`, or None where no surface of the scene hides from camera rays (the same walk,
    no render scene made)."""
    return _RENDER_SCENES.get(scene, bvh) if _hidden_from_camera(scene) else None


def _hidden_from_camera(scene) -> bool:
    """Whether a primitive of `scene` has a material hidden from camera rays (Material.hidden_from)."""
    hidden = [i for i, m in enumerate(scene.materials) if Rays(m.hidden_from) & Rays.CAMERA]
    # every mesh's, as the render scene takes them (a mesh without mesh_tri_material: material 0)
    used = [scene.sphere_material, *(scene.mesh_triangle_material(k) for k in range(scene.mesh_count))]
    return bool(hidden) and any(np.isin(np.asarray(a), hidden).any() for a in used)


def _kind_name(kind: int, prim: int) -> str | None:
    """What a summary says of the closest hit's kind: None for a miss (it said "triangle")."""
    return None if prim < 0 else "sphere" if kind else "triangle"


def _point(name: str, value) -> tuple:
    a = np.asarray(value)
    if a.shape != (3,) or a.dtype.kind not in "iuf":
        raise ValueError(f"{name} must be 3 numbers, got {value!r}")
    return tuple(float(c) for c in a.astype(np.float32))  # the traversal's precision, as Bvh.intersect


def _ray_fields(record) -> dict:
    """The ray and walk of a flat or two-level record as plain values (both summaries begin so)."""
    return {
        "pixel": list(record.pixel) if record.pixel else None,
        "origin": list(record.origin),
        "direction": list(record.direction),
        "tmin": record.tmin,
        "tmax": record.tmax,
        "traversal": record.traversal,
        "nodes_visited": record.nodes_visited,
    }
