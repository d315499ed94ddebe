"""The checked arguments and output arrays of the ray queries (`intersect`, `occluded`) that flat
and two-level trees share."""

from __future__ import annotations

import numpy as np

from . import _checks, _core

TRAVERSALS = tuple(_core.TRAVERSALS)  # of Bvh.intersect and the renderers (Vulkan: stack, stackless)

#: The arrays a ray query fills, in the order the core's intersect takes them.
HIT_FIELDS = {"t": np.float32, "prim": np.int32, "kind": np.uint8, "u": np.float32, "v": np.float32,
              "nodes_visited": np.uint32}  # fmt: skip


def _checked_rays(origins, directions, tmin, traversal: str, threads: int):
    """The arguments every ray query checks alike: (origins, directions, tmin, traversal, threads)."""
    origins = _checks.float32_array("origins", origins, (3,))
    directions = _checks.float32_array("directions", directions, (3,))
    if len(origins) != len(directions):
        raise ValueError(f"origins ({len(origins)}) and directions ({len(directions)}) differ in length")
    _checks.choice("traversal", traversal, TRAVERSALS)
    return origins, directions, _checks.real("tmin", tmin, 0.0), traversal, _checks.integer("threads", threads, 0, 4096)


def run_ray_query(
    core, origins, directions, tmin, tmax, traversal: str, threads: int, nodes_visited: bool, extra: dict | None = None
):
    """The checked arguments and output arrays of one `intersect` over a flat or two-level tree
    (`nodes_visited`: with that field; `extra`: more output fields, e.g. the instance), filled by
    `core.intersect`."""
    origins, directions, tmin, traversal, threads = _checked_rays(origins, directions, tmin, traversal, threads)
    tmax = _checks.real("tmax", tmax, 0.0)  # as occluded: a negative tmax is a caller's mistake, not all misses
    nodes_visited = _checks.flag("nodes_visited", nodes_visited)
    fields = {k: v for k, v in HIT_FIELDS.items() if nodes_visited or k != "nodes_visited"}
    out = {name: np.empty(len(origins), dtype) for name, dtype in {**fields, **(extra or {})}.items()}
    # None for the counts where not asked (the wide batch may then trace camera rays as packets)
    core.intersect(
        origins, directions, tmin, tmax, traversal, threads, *map(out.get, HIT_FIELDS), *map(out.get, extra or {})
    )
    return out


def run_occluded_query(core, origins, directions, tmin, tmax, traversal: str, threads: int) -> np.ndarray:
    """The checked arguments of one `occluded` over a flat or two-level tree, and its answer (bool,
    one per ray) from `core.occluded`. `tmax`: a number >= 0, or a float32 array of one per ray
    (which the core checks: a NaN or negative one raises ValueError naming the ray)."""
    origins, directions, tmin, traversal, threads = _checked_rays(origins, directions, tmin, traversal, threads)
    if isinstance(tmax, np.ndarray) and tmax.ndim > 0:  # one per ray (a 0-d array is a number: _checks.real)
        tmax_of = _checks.float32_array("tmax", tmax, ())
        if len(tmax_of) != len(origins):
            raise ValueError(f"tmax has {len(tmax_of)} entries for {len(origins)} rays (give one per ray, or a number)")
        tmax = np.inf
    else:
        tmax_of = None
        tmax = _checks.real("tmax", tmax, 0.0)
    out = np.empty(len(origins), np.bool_)
    core.occluded(origins, directions, tmin, tmax, tmax_of, traversal, threads, out)
    return out
