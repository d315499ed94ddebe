"""The per-frame dynamic-BVH experiment (issue 34; what the report could not run, its §1 and §5.2):
over the frames of an animation, each update policy keeps its own tree and updates it every frame
(`Bvh.update`); per frame and policy: the update's ms, the policy adaptive chose, the tree's SAH
cost beside a fresh build's, the subtrees rebuilt, and optionally the frame's trace time."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import asdict, dataclass

import numpy as np

from .bvh import Bvh, build
from .scene import Scene
from .update import UPDATE_POLICIES


@dataclass(frozen=True)
class FrameRow:
    """One policy's update at one frame (frame `first` is the build every policy starts from)."""

    frame: int
    policy: str  #: the policy asked for ("build" on the first frame)
    ran: str  #: what ran (adaptive's choice)
    update_ms: float
    sah_cost: float
    fresh_sah_cost: float
    subtrees_rebuilt: int
    primitives_rebuilt: int
    trace_ms: float  #: nan without a backend

    @property
    def sah_ratio(self) -> float:
        return self.sah_cost / self.fresh_sah_cost if self.fresh_sah_cost > 0 else math.nan

    def as_dict(self) -> dict:
        return {**asdict(self), "sah_ratio": self.sah_ratio}


def run_experiment(
    frame_triangles: Callable[[int], np.ndarray],
    frames: range,
    policies=UPDATE_POLICIES,
    *,
    trace: Callable[[np.ndarray, object], float] | None = None,
    progress: Callable[[float], object] | None = None,
) -> list[FrameRow]:
    """`frame_triangles(k)` gives frame k's triangles (the same count every frame); `trace(tris,
    bvh)` (optional) renders a frame and returns its trace ms. Every policy builds on the first
    frame (one thread, the default settings), then updates its tree at each next frame with a
    fresh build's SAH measured on the side."""
    policies = tuple(policies)
    for p in policies:
        if p not in UPDATE_POLICIES:
            raise ValueError(f"policy must be among {', '.join(UPDATE_POLICIES)}, got {p!r}")
    if len(frames) < 2:
        raise ValueError(f"the experiment needs at least two frames, got {len(frames)}")
    rows: list[FrameRow] = []
    first = frame_triangles(frames[0])

    def flat_tree(tris) -> Bvh:
        tree = build(Scene(triangles=tris), threads=1)
        assert isinstance(tree, Bvh)  # one mesh, no instances
        return tree

    start = flat_tree(first)
    trees = {p: flat_tree(first) for p in policies}
    traced = trace(first, start) if trace else math.nan
    built = start.stats
    for p in policies:
        rows.append(
            FrameRow(frames[0], p, "build", built["build_ms"], built["sah_cost"], built["sah_cost"], 0, 0, traced)
        )
    steps = (len(frames) - 1) * len(policies)
    done = 0
    for k in frames[1:]:
        tris = frame_triangles(k)
        if len(tris) != len(first):
            raise ValueError(
                f"frame {k} has {len(tris)} triangles, frame {frames[0]} {len(first)}: an update needs the same count"
            )
        for p in policies:
            tree = trees[p]
            s = tree.update(tris, policy=p, measure_fresh=True)  # rebuilds with the tree's settings (1 thread)
            t = trace(tris, tree) if trace else math.nan
            fresh = float(s.fresh_sah_cost) if s.fresh_sah_cost is not None else math.nan
            rows.append(FrameRow(k, p, s.policy, s.ms, s.sah_cost, fresh, s.subtrees_rebuilt, s.primitives_rebuilt, t))
            done += 1
            if progress is not None and progress(done / steps) is False:
                raise KeyboardInterrupt
    return rows


def summary(rows: list[FrameRow]) -> dict[str, dict]:
    """Per policy over the updated frames: total update ms, the worst and mean SAH ratio to a fresh
    build, and (rebuild present) the total as a share of rebuilding every frame."""
    out: dict[str, dict] = {}
    updated = [r for r in rows if r.ran != "build"]
    for p in dict.fromkeys(r.policy for r in updated):
        mine = [r for r in updated if r.policy == p]
        out[p] = {
            "total_ms": sum(r.update_ms for r in mine),
            "worst_sah_ratio": max(r.sah_ratio for r in mine),
            "mean_sah_ratio": float(np.mean([r.sah_ratio for r in mine])),
        }
    if "rebuild" in out and out["rebuild"]["total_ms"] > 0:
        for p in out:
            out[p]["share_of_rebuild"] = out[p]["total_ms"] / out["rebuild"]["total_ms"]
    return out
