"""Picking a box with a ray (issue 35: click in the viewport to pick the box under the cursor),
the way the overlay shows them: of the boxes in the shown depth range (only the leaves when the
overlay shows only leaves) that the ray enters before it reaches the geometry it hits, the deepest,
and of those the one it enters first; where it enters none, the leaf holding the primitive it hits.
The same for a two-level tree (`pick_two_level`), among the TLAS and BLAS boxes it shows."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import _checks
from .levels import MAX_OVERLAY_BOXES, TreeNode, blas_world_boxes, shown_boxes
from .node_data import NodeData

#: A box that holds the hit point is entered at or before the hit; the box wrapping the hit triangle
#: tightly is entered at the hit distance itself, up to rounding: this much later still counts (8
#: float32 steps of the distance; 1e-4 took boxes 0.018 behind a wall hit from 1,000 away).
HIT_SLACK = 2.0**-20


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
    return box_entry_distances(data.lo, data.hi, origin, direction)


def box_entry_distances(lo: np.ndarray, hi: np.ndarray, origin, direction) -> np.ndarray:
    """entry_distances for boxes (K,3) lo and hi."""
    o = np.asarray(origin, np.float64)
    d = np.asarray(direction, np.float64)
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = 1.0 / d
        t0 = (lo.astype(np.float64) - o) * inv
        t1 = (hi.astype(np.float64) - o) * inv
    near, far = np.minimum(t0, t1), np.maximum(t0, t1)
    # an axis the ray runs parallel to: inside the slab for every t, or never
    parallel = d == 0
    inside = (lo <= o) & (o <= hi)
    near = np.where(parallel, np.where(inside, -np.inf, np.inf), near)
    far = np.where(parallel, np.where(inside, np.inf, -np.inf), far)
    t_in, t_out = np.maximum(near.max(1), 0.0), far.min(1)
    return np.where(t_in <= t_out, t_in, np.inf)


def _depth_range(value) -> tuple[int, int]:
    """(min, max) depths, 0 <= min <= max <= 255 (a reversed or negative range picked silently)."""
    try:
        lo, hi = value
    except (TypeError, ValueError):
        raise TypeError(f"depth_range must be two depths (min, max), got {value!r}") from None
    lo, hi = _checks.integer("depth_range min", lo, 0, 255), _checks.integer("depth_range max", hi, 0, 255)
    if lo > hi:
        raise ValueError(f"depth_range must be (min, max) with min <= max, got ({lo}, {hi})")
    return lo, hi


def pick(
    bvh,
    origin,
    direction,
    depth_range: tuple[int, int] = (0, 255),
    *,
    leaves_only: bool = False,
    scene=None,
) -> Pick:
    """The box a ray picks among those the overlay shows (module docstring). `bvh` is a
    bvhlab.Bvh; `depth_range` the overlay's (min, max) depth, both included. `scene`: the
    bvhlab.Scene the tree was built over, where the picture is the tracer's (the Rendered
    viewport): the geometry the ray reaches is then what camera rays see, surfaces hidden from them
    (Material.hidden_from) passed by (_hit_record)."""
    origin, direction = _pick_ray(origin, direction)
    depth_range = _depth_range(depth_range)
    # one version throughout: a refit on another thread (the add-on's viewport worker) between the
    # boxes and the hit mixed two trees' (probe: 280 of 3,000 picks a box without its hit or a leaf
    # never entered)
    bvh = bvh._snapshot() if hasattr(bvh, "_snapshot") else bvh
    data = bvh.node_data(epo=False)  # boxes and depths: not the EPO pass (1M triangles: 1.4 s)
    record = _hit_record(bvh, origin, direction, scene)
    t_hit = float(record.t)
    t_enter = entry_distances(data, origin, direction)
    shown = (data.depth >= depth_range[0]) & (data.depth <= depth_range[1])
    if leaves_only:
        shown &= data.left < 0
    # entered (a finite entry: a ray that hits nothing still enters only the boxes it enters)
    candidates = np.flatnonzero(shown & np.isfinite(t_enter) & (t_enter <= t_hit * (1 + HIT_SLACK)))
    if len(candidates):
        deepest = candidates[data.depth[candidates] == data.depth[candidates].max()]
        node = int(deepest[np.lexsort((deepest, t_enter[deepest]))[0]])  # first entered; ties: lower index
        return Pick(node, "box", float(t_enter[node]), t_hit)
    if record.hit_leaf >= 0:
        return Pick(int(record.hit_leaf), "hit leaf", float(t_enter[record.hit_leaf]), t_hit)
    return Pick(None, "nothing", float("inf"), t_hit)


def _hit_record(bvh, origin, direction, scene):
    """The stack walk's record of the pick ray through `bvh` (a Bvh or an InstancedBvh): to the
    closest surface, or with `scene` to the closest its camera rays see (the tracer's rule, from
    the scene's render scene: ray_record.trace_pixel's)."""
    from .ray_record import camera_rule, record_of

    o, d = origin.astype(np.float32), direction.astype(np.float32)
    rule = None if scene is None else camera_rule(scene, bvh)
    return record_of(bvh, o, d, 0.0, float("inf"), "stack", camera_of=rule)


def _pick_ray(origin, direction) -> tuple[np.ndarray, np.ndarray]:
    given = np.asarray(origin, np.float64).reshape(3), np.asarray(direction, np.float64).reshape(3)
    # the float32 ray the trace walks, for the boxes' entries too: a float64 origin's entries and
    # the float32 trace's hit parted by a float32 step of the origin (a wall 0.01 away from x =
    # 1,000 was missed in 99 of 200 picks); checked as float32 holds it, named as given (a
    # direction of 1e-50 became 0 there, an origin of 1e39 inf, and the core's words said so)
    with np.errstate(over="ignore"):
        origin, direction = (v.astype(np.float32).astype(np.float64) for v in given)
    if not (np.all(np.isfinite(origin)) and np.all(np.isfinite(direction)) and np.any(direction != 0)):
        raise ValueError(
            "a pick ray needs a finite origin and a non-zero direction float32 holds, "
            f"got {given[0].tolist()}, {given[1].tolist()}"
        )
    return origin, direction


@dataclass(frozen=True)
class TwoLevelPick:
    """What a ray picked in a two-level tree: `box` (a TreeNode, None when nothing), how, and the
    distances as Pick's."""

    box: TreeNode | None
    how: str
    t_enter: float
    t_hit: float


def pick_two_level(
    bvh,
    origin,
    direction,
    level: str = "both",
    depth_range: tuple[int, int] = (0, 255),
    *,
    leaves_only: bool = False,
    cap: int = MAX_OVERLAY_BOXES,
    scene=None,
) -> TwoLevelPick:
    """The box a ray picks among those the overlay shows of a two-level tree (`bvh` a
    bvhlab.InstancedBvh; `level`, the depth range, leaves-only and the cap as
    bvhlab.inspect.levels.shown_boxes takes them): the rule of `pick` with BLAS boxes deeper than
    TLAS boxes (a BLAS box lies inside its instance's TLAS leaf); where the ray enters none, the
    BLAS leaf of the hit primitive in its instance (the TLAS leaf of the hit instance when only
    the TLAS is shown). `scene` as pick's."""
    origin, direction = _pick_ray(origin, direction)
    depth_range = _depth_range(depth_range)
    bvh = bvh.snapshot()  # one TLAS and one set of meshes throughout (another thread may place)
    shown = shown_boxes(bvh, level, depth_range[0], depth_range[1], leaves_only, cap)
    record = _hit_record(bvh, origin, direction, scene)
    t_hit = float(record.t)
    t_enter = box_entry_distances(shown.lo, shown.hi, origin, direction)
    candidates = np.flatnonzero(np.isfinite(t_enter) & (t_enter <= t_hit * (1 + HIT_SLACK)))
    if len(candidates):
        # deepest: BLAS over TLAS, then depth; then first entered; ties: earlier in the shown order
        deeper = -shown.depth[candidates].astype(np.int64)  # (as ints: the arrays are unsigned)
        lower_level = -shown.level[candidates].astype(np.int64)
        k = candidates[np.lexsort((candidates, t_enter[candidates], deeper, lower_level))[0]]
        return TwoLevelPick(shown.tree_node(int(k)), "box", float(t_enter[k]), t_hit)
    if record.instance < 0:
        return TwoLevelPick(None, "nothing", float("inf"), t_hit)
    if level == "tlas":
        node = bvh.tlas_leaf_of(record.instance)
        box = TreeNode("tlas", node) if node >= 0 else None
    else:
        box = TreeNode("blas", record.hit_leaf, record.instance)
    if box is None:
        return TwoLevelPick(None, "nothing", float("inf"), t_hit)
    lo, hi = node_world_box(bvh, box)
    return TwoLevelPick(box, "hit leaf", float(box_entry_distances(lo[None], hi[None], origin, direction)[0]), t_hit)


def node_world_box(bvh, box: TreeNode) -> tuple[np.ndarray, np.ndarray]:
    """(lo, hi) float32 (3,) of a two-level tree's node in the world, as the overlay draws it."""
    if box.level == "tlas":
        data = bvh.tlas_node_data()
        return data.lo[box.node], data.hi[box.node]
    mesh_of, _ = bvh.instances
    nodes = bvh.meshes[int(mesh_of[box.instance])].nodes
    lo, hi = blas_world_boxes(
        bvh, nodes["lo"][box.node][None], nodes["hi"][box.node][None], np.array([box.node]), np.array([box.instance])
    )
    return lo[0, 0].astype(np.float32), hi[0, 0].astype(np.float32)
