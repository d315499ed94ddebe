"""Picking a box with a ray (issue 35: click in the viewport to pick the box under the cursor),
the way the overlay shows them: of the boxes in the shown depth range (only the leaves when the
overlay shows only leaves) that the ray enters before it reaches the geometry it hits, the deepest,
and of those the one it enters first; where it enters none, the leaf holding the primitive it hits."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .node_data import NodeData

#: A box that holds the hit point is entered at or before the hit; the box wrapping the hit triangle
#: tightly is entered at the hit distance itself, up to rounding: this much later still counts.
HIT_SLACK = 1e-4


@dataclass(frozen=True)
class Pick:
    """What a ray picked: the node (None when nothing), how (`"box"`: entered among the shown
    boxes, `"hit leaf"`: the leaf of the hit primitive), and the distance along the ray at which it
    enters the box (0 when it starts inside) and at which it hits geometry (inf on a miss)."""

    node: int | None
    how: str
    t_enter: float
    t_hit: float


def entry_distances(data: NodeData, origin, direction) -> np.ndarray:
    """Each node's slab test (Kay and Kajiya 1986) for the ray origin + t·direction, t ≥ 0: the
    distance at which the ray enters the box (0 inside it), +inf where it misses."""
    o = np.asarray(origin, np.float64)
    d = np.asarray(direction, np.float64)
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = 1.0 / d
        t0 = (data.lo.astype(np.float64) - o) * inv
        t1 = (data.hi.astype(np.float64) - o) * inv
    near, far = np.minimum(t0, t1), np.maximum(t0, t1)
    # an axis the ray runs parallel to: inside the slab for every t, or never
    parallel = d == 0
    inside = (data.lo <= o) & (o <= data.hi)
    near = np.where(parallel, np.where(inside, -np.inf, np.inf), near)
    far = np.where(parallel, np.where(inside, np.inf, -np.inf), far)
    t_in, t_out = np.maximum(near.max(1), 0.0), far.min(1)
    return np.where(t_in <= t_out, t_in, np.inf)


def pick(
    bvh,
    origin,
    direction,
    depth_range: tuple[int, int] = (0, 255),
    *,
    leaves_only: bool = False,
) -> Pick:
    """The box a ray picks among those the overlay shows (module docstring). `bvh` is a
    bvhlab.Bvh; `depth_range` the overlay's (min, max) depth, both included."""
    origin = np.asarray(origin, np.float64).reshape(3)
    direction = np.asarray(direction, np.float64).reshape(3)
    if not (np.all(np.isfinite(origin)) and np.all(np.isfinite(direction)) and np.any(direction != 0)):
        raise ValueError(f"a pick ray needs a finite origin and a finite non-zero direction, got {origin}, {direction}")
    data = bvh.node_data()
    record = bvh.trace_ray(origin.astype(np.float32), direction.astype(np.float32))
    t_hit = float(record.t)
    t_enter = entry_distances(data, origin, direction)
    shown = (data.depth >= depth_range[0]) & (data.depth <= depth_range[1])
    if leaves_only:
        shown &= data.left < 0
    candidates = np.flatnonzero(shown & (t_enter <= t_hit * (1 + HIT_SLACK)))
    if len(candidates):
        deepest = candidates[data.depth[candidates] == data.depth[candidates].max()]
        node = int(deepest[np.lexsort((deepest, t_enter[deepest]))[0]])  # first entered; ties: lower index
        return Pick(node, "box", float(t_enter[node]), t_hit)
    if record.hit_leaf >= 0:
        return Pick(int(record.hit_leaf), "hit leaf", float(t_enter[record.hit_leaf]), t_hit)
    return Pick(None, "nothing", float("inf"), t_hit)
