"""The per-frame dynamic-BVH experiment (issue 34; what the report could not run, its §1 and §5.2):
over the frames of an animation, each update policy keeps its own tree and updates it every frame
(`Bvh.update`); per frame and policy: the update's ms, the policy adaptive chose, the tree's SAH
cost beside a fresh build's, the subtrees rebuilt, and optionally the frame's trace time."""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass

import numpy as np

from .bvh import Bvh, build
from .instanced import InstancedBvh
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
    #: adaptive: the subtrees whose boxes the levels above them were rebuilt over (0: not; `ran`
    #: says "partial" either way, the policy adaptive chose below them: UpdateStats.top_boxes)
    top_boxes: int = 0

    @property
    def sah_ratio(self) -> float:
        return self.sah_cost / self.fresh_sah_cost if self.fresh_sah_cost > 0 else math.nan

    def as_dict(self) -> dict:
        return {**asdict(self), "sah_ratio": self.sah_ratio}


#: The row of an instanced scene's two-level tree (not an update policy): the meshes' trees kept
#: (updated where a mesh deformed), a new TLAS over the moved instances.
TWO_LEVEL = "two-level"


def run_experiment(
    frame_geometry: Callable[[int], np.ndarray | Scene],
    frames: range,
    policies=UPDATE_POLICIES,
    *,
    trace: Callable[[Scene, object], float] | None = None,
    progress: Callable[[float], object] | None = None,
) -> list[FrameRow]:
    """`frame_geometry(k)` gives frame k's triangles (the same count every frame), or its Scene;
    `trace(geometry, bvh)` (optional: a Scene of the frame's triangles and spheres) renders a frame
    and returns its trace ms. Every policy builds on
    the first frame (one thread, the default settings), then updates its own tree at each next
    frame; a fresh build per frame gives the SAH cost the policies are compared with. An
    instanced Scene's policies update trees over its flattened triangles, and a TWO_LEVEL row per
    frame times the two-level tree's update (`InstancedBvh.place`, `update_mesh` for a deformed
    mesh), whose SAH is not comparable with a flat tree's (NaN)."""
    policies = tuple(policies)
    for p in policies:
        if p not in UPDATE_POLICIES:
            raise ValueError(f"policy must be among {', '.join(UPDATE_POLICIES)}, got {p!r}")
    if len(frames) < 2:
        raise ValueError(f"the experiment needs at least two frames, got {len(frames)}")
    rows: list[FrameRow] = []
    first_scene = as_scene(frame_geometry(frames[0]))
    first = _flat(first_scene)
    two_level = _TwoLevel(first_scene) if first_scene.is_instanced else None

    start = _flat_tree(first)
    trees = {p: _flat_tree(first) for p in policies}
    traced = trace(first, start) if trace else math.nan
    built = start.stats
    for p in policies:
        rows.append(
            FrameRow(frames[0], p, "build", built["build_ms"], built["sah_cost"], built["sah_cost"], 0, 0, traced)
        )
    if two_level is not None:
        rows.append(two_level.first_row(frames[0]))
    steps = (len(frames) - 1) * len(policies)
    done = 0
    for k in frames[1:]:
        scene = as_scene(frame_geometry(k))
        flat = _flat(scene)
        for kind, now, then in (
            ("triangles", flat.triangles, first.triangles),
            ("spheres", flat.spheres, first.spheres),
        ):
            if len(now) != len(then):
                raise ValueError(
                    f"frame {k} has {len(now)} {kind}, frame {frames[0]} {len(then)}: an update needs the same count"
                )
        fresh = float(_flat_tree(flat).stats["sah_cost"])  # the same settings as every policy's tree
        spheres = flat.spheres if len(flat.spheres) else None
        for p in policies:
            tree = trees[p]
            s = tree.update(flat.triangles, spheres, policy=p)  # rebuilds with the tree's settings (1 thread)
            t = trace(flat, tree) if trace else math.nan
            # the tree's SAH cost as `fresh` is summed (Bvh.stats), not the update's own figure, which
            # sums the same terms in another order: a rebuild's ratio came out 0.99999997
            sah = float(tree.stats["sah_cost"])
            rows.append(
                FrameRow(k, p, s.policy, s.ms, sah, fresh, s.subtrees_rebuilt, s.primitives_rebuilt, t, s.top_boxes)
            )
            done += 1
            if progress is not None and progress(done / steps) is False:
                raise KeyboardInterrupt
        if two_level is not None:
            rows.append(two_level.update(k, scene))
    return rows


def as_scene(geometry) -> Scene:
    return geometry if isinstance(geometry, Scene) else Scene(triangles=geometry)


def _flat(scene: Scene) -> Scene:
    """The frame's geometry as one mesh: its triangles (an instanced scene's flattened) and its
    analytic spheres (they move too: the experiment read triangles alone, a rising sphere left
    every row at a SAH ratio of 1 and the two-level tree's hits where it started)."""
    flat = scene.flattened() if scene.is_instanced else scene
    return Scene(triangles=flat.triangles, spheres=flat.spheres)


def _flat_tree(geometry: Scene) -> Bvh:
    tree = build(geometry, threads=1)
    assert isinstance(tree, Bvh)  # one mesh, no instances
    return tree


class _TwoLevel:
    """The two-level tree of an instanced animation, updated frame by frame: a deformed mesh's
    tree by the adaptive policy, then a new TLAS over the instances where they now are."""

    def __init__(self, scene: Scene):
        tree = build(scene, threads=1)
        assert isinstance(tree, InstancedBvh)
        self.tree, self.meshes = tree, [scene.mesh_triangles(k) for k in range(scene.mesh_count)]
        self.spheres = scene.spheres  # mesh 0's

    def _same(self, k: int, scene: Scene) -> bool:
        """Whether mesh k is as it was (mesh 0: its spheres too)."""
        same = np.array_equal(scene.mesh_triangles(k), self.meshes[k])
        return same and (k != 0 or np.array_equal(scene.spheres, self.spheres))

    def first_row(self, frame: int) -> FrameRow:
        s = self.tree.stats
        build_ms = sum(m.stats["build_ms"] for m in self.tree.meshes) + s["tlas_build_ms"]
        return FrameRow(frame, TWO_LEVEL, "build", build_ms, math.nan, math.nan, 0, 0, math.nan)

    def update(self, frame: int, scene: Scene) -> FrameRow:
        if scene.mesh_count != len(self.meshes):
            raise ValueError(f"frame {frame} has {scene.mesh_count} meshes, the first frame {len(self.meshes)}")
        # which meshes deformed: the exporter knows (LiveScene's SyncReport); not part of the time
        changed = [k for k in range(scene.mesh_count) if not self._same(k, scene)]
        start = time.perf_counter()
        for k in changed:
            counts = (len(self.meshes[k]), len(self.spheres) if k == 0 else 0)
            self.meshes[k] = scene.mesh_triangles(k)
            self.spheres = scene.spheres
            spheres = scene.spheres if k == 0 else None
            if counts == (len(self.meshes[k]), len(scene.spheres) if k == 0 else 0):
                self.tree.meshes[k].update(self.meshes[k], spheres)  # place() follows it
            else:  # one mesh gained what another lost (the frame's total the same): its tree anew
                self.tree.update_mesh(k, self.meshes[k], spheres)
        self.tree.place(*scene.instances())
        ms = (time.perf_counter() - start) * 1e3
        ran = "tlas" + (f"+{len(changed)} meshes" if changed else "")  # the meshes updated: no subtrees
        return FrameRow(frame, TWO_LEVEL, ran, ms, math.nan, math.nan, 0, 0, math.nan)


def summary(rows: list[FrameRow]) -> dict[str, dict]:
    """Per policy over the updated frames: total update ms, the worst and mean SAH ratio to a fresh
    build, and (rebuild present) the total as a share of rebuilding every frame."""
    out: dict[str, dict] = {}
    updated = [r for r in rows if r.ran != "build"]
    for p in dict.fromkeys(r.policy for r in updated):
        mine = [r for r in updated if r.policy == p]
        ratios = [r.sah_ratio for r in mine]  # NaN for the two-level rows
        out[p] = {
            "total_ms": sum(r.update_ms for r in mine),
            "worst_sah_ratio": max(ratios) if not any(map(math.isnan, ratios)) else math.nan,
            "mean_sah_ratio": float(np.mean(ratios)),
        }
    if "rebuild" in out and out["rebuild"]["total_ms"] > 0:
        for p in out:
            out[p]["share_of_rebuild"] = out[p]["total_ms"] / out["rebuild"]["total_ms"]
    return out
