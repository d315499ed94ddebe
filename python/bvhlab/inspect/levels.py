"""The boxes of a two-level tree (issue 34) as the viewport shows them, each with what it is: a
TLAS node (world space), or a node of an instance's mesh tree moved into the world by the
instance's transform (Arvo's box; a root's is the TLAS's box of its instance, blas_world_boxes),
in a depth range that applies within each level. Bounded: a scene of 10,000 instances would have
millions of BLAS boxes, so at most `cap` are kept, the BLAS boxes of the first instances that fit.
The overlay draws these boxes (addon/overlay/levels.py) and Pick Box picks among them
(bvhlab.inspect.pick.pick_two_level), so both see the same boxes."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: The most boxes the overlay draws of a two-level tree (a few MB of texture; one instanced draw).
MAX_OVERLAY_BOXES = 200_000
LEVELS = ("tlas", "blas", "both")
#: `ShownBoxes.level` values.
TLAS, BLAS = 0, 1


@dataclass(frozen=True)
class TreeNode:
    """A node of a two-level tree: of the TLAS (`instance` -1), or `node` of the mesh tree of
    instance `instance` (`InstancedBvh.meshes[mesh of the instance]`)."""

    level: str  #: "tlas" or "blas"
    node: int
    instance: int = -1


@dataclass
class ShownBoxes:
    """Boxes sorted by depth within their own level (stable: TLAS boxes, then each mesh's
    instances' boxes, instance by instance): lo, hi (K,3) float32 in the world, depth (K,) uint8,
    level (K,) uint8 (TLAS or BLAS), instance (K,) int32 (-1 for TLAS boxes), node (K,) int32 (in
    the TLAS or in the instance's mesh tree); `instances_shown` of `instances` have their BLAS
    boxes among them."""

    lo: np.ndarray
    hi: np.ndarray
    depth: np.ndarray
    level: np.ndarray
    instance: np.ndarray
    node: np.ndarray
    instances_shown: int
    instances: int
    tlas_shown: int = 0  #: TLAS boxes kept (the shallowest first) of `tlas_boxes` in the range
    tlas_boxes: int = 0

    @property
    def note(self) -> str:
        """What the cap left out, in words ("" when nothing)."""
        return _notes(self.tlas_shown, self.tlas_boxes, self.instances_shown, self.instances)

    def tree_node(self, k: int) -> TreeNode:
        """What box k is."""
        if self.level[k] == TLAS:
            return TreeNode("tlas", int(self.node[k]))
        return TreeNode("blas", int(self.node[k]), int(self.instance[k]))


def _notes(tlas_shown: int, tlas_boxes: int, instances_shown: int, instances: int) -> str:
    """What the cap left out of each level, in words, joined ("" when nothing)."""
    parts = []
    if tlas_shown != tlas_boxes:
        parts.append(
            f"the {tlas_shown:,} shallowest of {tlas_boxes:,} TLAS boxes (at most {MAX_OVERLAY_BOXES:,} boxes)"
        )
    if instances_shown != instances:
        parts.append(
            f"BLAS boxes of {instances_shown:,} of {instances:,} instances (at most {MAX_OVERLAY_BOXES:,} boxes)"
        )
    return "; ".join(parts)


def _instances_within(counts: np.ndarray, budget: int) -> int:
    """How many instances, first to last, have all their boxes (`counts`, one per instance) in
    `budget` boxes."""
    return int(np.searchsorted(np.cumsum(counts), max(budget, 0), side="right"))


def cap_note(bvh, level: str, depth_min: int, depth_max: int, leaves_only: bool = False, cap: int = MAX_OVERLAY_BOXES):
    """`shown_boxes(...).note` for the same arguments, from the counts only (no box is made): what
    F12 and the Rendered viewport say their overlay pass leaves out."""
    if level not in LEVELS:
        raise ValueError(f"level must be one of {LEVELS}, got {level!r}")
    mesh_of = np.asarray(bvh.instances[0], np.int64)
    tlas = boxes = 0
    if level in ("tlas", "both"):
        data = bvh.tlas_node_data()
        boxes = len(nodes_in_range(data.depth, data.left < 0, depth_min, depth_max, leaves_only))
        tlas = min(boxes, cap)
    if level == "tlas":
        return _notes(tlas, boxes, 0, 0)
    per_mesh = [len(nodes_in_range(m.depths, m.is_leaf, depth_min, depth_max, leaves_only)) for m in bvh.meshes]
    counts = np.array(per_mesh, np.int64)[mesh_of]
    return _notes(tlas, boxes, _instances_within(counts, cap - tlas), len(mesh_of))


def world_boxes(lo: np.ndarray, hi: np.ndarray, transforms: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Boxes (B,3) moved by each of the (N,3,4) object-to-world transforms: (N,B,3) lo and hi, the
    tightest world boxes of the moved boxes (Arvo 1990, "Transforming axis-aligned bounding boxes":
    the centre moves by the matrix, the half extents by its absolute values)."""
    m = transforms.astype(np.float64)
    centre = (lo.astype(np.float64) + hi) / 2
    half = (hi.astype(np.float64) - lo) / 2
    linear = m[:, :, :3].transpose(0, 2, 1)  # row vectors: p @ Mᵀ
    moved = centre[None] @ linear + m[:, None, :, 3]
    extent = half[None] @ np.abs(linear)
    return moved - extent, moved + extent


def blas_world_boxes(bvh, lo: np.ndarray, hi: np.ndarray, node: np.ndarray, instances: np.ndarray):
    """Nodes `node` (B,) of one mesh's tree, boxes `lo`, `hi` (B,3), in the world for each of
    `instances` (N,) of that mesh: (N,B,3) lo and hi, world_boxes of each, but a BLAS root's box is
    its instance's world box, the box the TLAS holds (InstancedBvh.world_boxes: its mesh's top
    eight boxes moved, tighter than the moved root box where the instance is rotated), so that a
    BLAS root never sticks out of its TLAS leaf when stepping between the levels. Boxes below the
    root are each moved by Arvo's method: they hold their geometry, but under a rotation one can
    stick out of the root's tighter box (a box moved whole is larger than its moved children)."""
    _, transforms = bvh.instances
    world_lo, world_hi = world_boxes(lo, hi, transforms[instances])
    root = np.asarray(node) == 0
    if root.any() and len(instances):
        instance_lo, instance_hi = bvh.world_boxes()
        world_lo[:, root] = instance_lo[instances][:, None]
        world_hi[:, root] = instance_hi[instances][:, None]
    return world_lo, world_hi


def nodes_in_range(depth: np.ndarray, leaf: np.ndarray, depth_min: int, depth_max: int, leaves_only: bool):
    """The nodes of one tree in the depth range (only leaves with `leaves_only`), by depth and in
    depth-first order within a depth: the order of Bvh.boxes."""
    chosen = np.flatnonzero((depth >= depth_min) & (depth <= depth_max) & (leaf | (not leaves_only)))
    return chosen[np.argsort(depth[chosen], kind="stable")]


def shown_boxes(
    bvh, level: str, depth_min: int, depth_max: int, leaves_only: bool = False, cap: int = MAX_OVERLAY_BOXES
) -> ShownBoxes:
    """The boxes of `bvh` (a bvhlab.InstancedBvh) shown for `level` ("tlas", "blas", "both") in
    the depth range, at most `cap` of them (module docstring)."""
    if level not in LEVELS:
        raise ValueError(f"level must be one of {LEVELS}, got {level!r}")
    bvh = bvh.snapshot()  # one TLAS and one set of meshes throughout (another thread may place)
    mesh_of, transforms = bvh.instances
    mesh_of = np.asarray(mesh_of, np.int64)
    parts = []  # (lo, hi, depth, level, instance, node)
    tlas_boxes = tlas_shown = 0
    if level in ("tlas", "both"):
        data = bvh.tlas_node_data()
        ids = nodes_in_range(data.depth, data.left < 0, depth_min, depth_max, leaves_only)
        # the cap bounds the TLAS's boxes too (1,000,000 instances: 2,000,000 boxes, 61 MB of texture,
        # 1.3-1.7 s to make at every change of the depth range): the shallowest, as sorted
        tlas_boxes, ids = len(ids), ids[:cap]
        tlas_shown = len(ids)
        parts.append((data.lo[ids], data.hi[ids], data.depth[ids], TLAS, np.full(len(ids), -1), ids))
    shown = 0
    if level in ("blas", "both"):
        per_mesh = []
        for m in bvh.meshes:
            nodes = m.nodes
            ids = nodes_in_range(m.depths, m.is_leaf, depth_min, depth_max, leaves_only)
            per_mesh.append((nodes["lo"][ids], nodes["hi"][ids], m.depths[ids], ids))
        counts = np.array([len(b[3]) for b in per_mesh], np.int64)[mesh_of]
        shown = _instances_within(counts, cap - tlas_shown)
        for k, (lo, hi, depth, ids) in enumerate(per_mesh):
            chosen = np.flatnonzero(mesh_of[:shown] == k)
            if len(chosen) and len(ids):
                world_lo, world_hi = blas_world_boxes(bvh, lo, hi, ids, chosen)
                parts.append(
                    (
                        world_lo.reshape(-1, 3),
                        world_hi.reshape(-1, 3),
                        np.tile(depth, len(chosen)),
                        BLAS,
                        np.repeat(chosen, len(ids)),
                        np.tile(ids, len(chosen)),
                    )
                )
    lo, hi, depth, levels, instance, node = _joined(parts)
    order = np.argsort(depth, kind="stable")
    blas_shown = level != "tlas"
    return ShownBoxes(
        lo[order].astype(np.float32),
        hi[order].astype(np.float32),
        depth[order].astype(np.uint8),
        levels[order].astype(np.uint8),
        instance[order].astype(np.int32),
        node[order].astype(np.int32),
        shown if blas_shown else 0,
        len(mesh_of) if blas_shown else 0,
        tlas_shown,
        tlas_boxes,
    )


def _joined(parts) -> tuple:
    if not parts:
        empty = np.zeros(0, np.int64)
        return np.zeros((0, 3)), np.zeros((0, 3)), empty, empty, empty, empty
    return (
        np.concatenate([np.asarray(p[0], np.float64).reshape(-1, 3) for p in parts]),
        np.concatenate([np.asarray(p[1], np.float64).reshape(-1, 3) for p in parts]),
        np.concatenate([np.asarray(p[2], np.int64) for p in parts]),
        np.concatenate([np.full(len(p[2]), p[3], np.int64) for p in parts]),
        np.concatenate([np.asarray(p[4], np.int64) for p in parts]),
        np.concatenate([np.asarray(p[5], np.int64) for p in parts]),
    )
