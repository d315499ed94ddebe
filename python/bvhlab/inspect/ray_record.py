"""`RayRecord`: what one ray's traversal did, recorded by the traversal code itself
(core_cpp/include/bvhlab/ray_record.h), and `trace_pixel`: the same for a pixel's primary ray,
made by the tracer's own camera code."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .. import _checks, _core

#: Traversals that can be recorded: those over the binary nodes (the wide tree has none to name).
RECORD_TRAVERSALS = ("stack", "stackless")


@dataclass(frozen=True)
class RayRecord:
    """Boxes tested in order (`box_nodes`, with `box_hit`: whether the ray entered), primitives
    tested in order (`prim_slots` in the tree's leaf order, `prim_refs` their references with
    REF_SPHERE_BIT for spheres, `prim_leaf` the leaf, `prim_box_test` how many box tests came
    before, `prim_closer` whether it became the closest hit), and the closest hit as
    `Bvh.intersect` returns it (t, prim, kind, u, v) with its slot and leaf (-1 on a miss).
    `len(box_nodes)` is the box-test count `Bvh.intersect` reports as nodes_visited."""

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
                out.append({"step": "box", "node": int(self.box_nodes[step]), "hit": bool(self.box_hit[step])})
        return out

    def summary(self) -> dict:
        """Counts and the closest hit as plain values (what the CLI prints and writes)."""
        return {
            "pixel": list(self.pixel) if self.pixel else None,
            "origin": list(self.origin),
            "direction": list(self.direction),
            "tmin": self.tmin,
            "tmax": self.tmax,
            "traversal": self.traversal,
            "box_tests": self.box_tests,
            "box_hits": self.box_hits,
            "prim_tests": self.prim_tests,
            "t": self.t,
            "prim": self.prim,
            "kind": "sphere" if self.kind else "triangle",
            "hit_leaf": self.hit_leaf,
            "hit_slot": self.hit_slot,
        }


def record(core_bvh, origin, direction, tmin: float, tmax: float, traversal: str, pixel=None) -> RayRecord:
    """The record of one ray through `core_bvh` (a `_core.Bvh`); types checked here, values in C++."""
    origin = _point("origin", origin)
    direction = _point("direction", direction)
    _checks.choice("traversal", traversal, RECORD_TRAVERSALS)
    tmin, tmax = _checks.real("tmin", tmin), _checks.real("tmax", tmax)
    d = core_bvh.trace_ray(origin, direction, tmin, tmax, traversal)
    for value in d.values():
        if isinstance(value, np.ndarray):
            value.flags.writeable = False
    d.pop("revision")
    return RayRecord(origin, direction, tmin, tmax, traversal, pixel=pixel, **d)


def trace_pixel(scene, bvh, x: int, y: int, *, width: int, height: int, options=None, camera=None, sample: int = 0):
    """The record of the primary ray of sample `sample` of pixel (x, y) (row 0 at the top) of a
    `width`×`height` render of `scene` with `bvh`: the ray the tracer traces there (its camera
    code and clipping; the overlay's lines are not drawn), walked by the traversal of
    `options.traversal` (stack or stackless), whose box tests are the pixel's cost at one sample."""
    from .._render_scene import SceneCache
    from .._render_settings import render_settings
    from ..render_options import options_from

    options = options_from(options, {})
    settings = render_settings(scene, bvh, width, height, options, camera)
    render_scene = SceneCache().get(scene, bvh)
    x = _checks.integer("x", x, 0, 2**32 - 1)
    y = _checks.integer("y", y, 0, 2**32 - 1)
    sample = _checks.integer("sample", sample, 0, 2**32 - 1)
    origin, direction, tmin, tmax = _core.pixel_ray(render_scene, settings, x, y, sample)
    return record(bvh._core, origin, direction, tmin, tmax, options.traversal, pixel=(x, y, sample))


def _point(name: str, value) -> tuple:
    a = np.asarray(value)
    if a.shape != (3,) or a.dtype.kind not in "iuf":
        raise ValueError(f"{name} must be 3 numbers, got {value!r}")
    return tuple(float(c) for c in a.astype(np.float32))  # the traversal's precision, as Bvh.intersect
