"""The boxes of a two-level tree (issue 34) as the overlays draw them: the TLAS's node boxes (world
space), the BLASes' node boxes moved into the world by each instance, or both, in a depth range
that applies within each level. Bounded: a scene of 10,000 instances would make millions of BLAS
boxes, so at most MAX_OVERLAY_BOXES are kept, the BLAS boxes of the first instances that fit (the
panel says how many). One definition for the add-on's viewport overlay (addon/overlay) and the
tracers' overlay pass (`RenderOptions.overlay_level`, _render_scene.py). The tests compare it with
their own computation."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: The most boxes the overlay draws of a two-level tree (a few MB of texture; one instanced draw).
MAX_OVERLAY_BOXES = 200_000
LEVELS = ("tlas", "blas", "both")


@dataclass
class LevelBoxes:
    """Boxes sorted by depth (within their own level): lo, hi (K,3) float32, depth (K,) uint8;
    `instances_shown` of `instances` have their BLAS boxes among them."""

    lo: np.ndarray
    hi: np.ndarray
    depth: np.ndarray
    instances_shown: int
    instances: int

    @property
    def note(self) -> str:
        """What the cap left out, in words ("" when nothing)."""
        if self.instances_shown == self.instances:
            return ""
        return (
            f"BLAS boxes of {self.instances_shown:,} of {self.instances:,} instances "
            f"(at most {MAX_OVERLAY_BOXES:,} boxes)"
        )


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


def two_level_boxes(
    bvh, level: str, depth_min: int, depth_max: int, leaves_only: bool = False, cap: int = MAX_OVERLAY_BOXES
) -> LevelBoxes:
    """The boxes of `bvh` (a bvhlab.InstancedBvh) that the overlay draws for `level` ("tlas",
    "blas", "both") in the depth range, at most `cap` of them."""
    if level not in LEVELS:
        raise ValueError(f"level must be one of {LEVELS}, got {level!r}")
    mesh_of, transforms = bvh.instances
    mesh_of = np.asarray(mesh_of, np.int64)
    parts = []
    if level in ("tlas", "both"):
        parts.append(bvh.tlas_boxes(depth_min, depth_max, leaves_only=leaves_only))
    shown = 0
    if level in ("blas", "both"):
        per_mesh = [m.boxes(depth_min, depth_max, leaves_only=leaves_only) for m in bvh.meshes]
        counts = np.array([len(b[0]) for b in per_mesh], np.int64)[mesh_of]
        budget = max(cap - sum(len(p[0]) for p in parts), 0)
        shown = int(np.searchsorted(np.cumsum(counts), budget, side="right"))
        for k, (lo, hi, depth) in enumerate(per_mesh):
            chosen = np.flatnonzero(mesh_of[:shown] == k)
            if len(chosen) and len(lo):
                world_lo, world_hi = world_boxes(lo, hi, transforms[chosen])
                parts.append((world_lo.reshape(-1, 3), world_hi.reshape(-1, 3), np.tile(depth, len(chosen))))
    if not parts:
        parts.append((np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0, np.uint8)))
    lo, hi, depth = (np.concatenate([p[i] for p in parts]) for i in range(3))
    order = np.argsort(depth, kind="stable")
    instances = len(mesh_of) if level != "tlas" else 0
    return LevelBoxes(
        lo[order].astype(np.float32),
        hi[order].astype(np.float32),
        depth[order].astype(np.uint8),
        shown if level != "tlas" else 0,
        instances,
    )
