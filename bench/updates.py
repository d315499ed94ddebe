"""Issue 34's two update targets, measured through the Python API in one run, one core:

1. refit of a 1M-triangle mesh against its rebuild (target: refit >= 10x faster): a 708x708 grid
   (1,002,528 triangles, bench/cpp/refit_peers.cpp's) with a travelling wave; `Bvh.refit` and
   `bvhlab.build` interleaved, the least of `--repeat` each;
2. the update policies over the bundled generated animations (bvhlab.library.animations: the
   wave, the frames of blender_scenes/wave_anim.blend, 250,632 triangles; the crowd, 300 knots
   flying among pillars, 150,272), `--frames` frames each, every policy keeping its own tree
   (target: adaptive within 1.10x of a fresh build's SAH on every frame, at <= 1/3 of the time of
   rebuilding every frame). Per frame and policy: update ms, what ran, SAH cost against a fresh
   build's, and the primitives and top boxes (adaptive's rebuild_top) rebuilt.

Prints a table; `--json` writes bench/results/updates.json.

    .venv/bin/python bench/updates.py [--json] [--frames 24] [--repeat 7]

`--interleaved wave,crowd,FRAMES.npz` instead measures adaptive against rebuilding every frame in
thread CPU time (the process's other threads and the shared machine's other jobs not counted),
the two interleaved frame by frame in one process, with the adaptive settings given as JSON
(`--configs '{"label": {"top_intact_primitives": 0}, ...}'`, each its own tree; default: the
defaults); an .npz holds one (N, 3, 3) array per frame named f0, f1, ... (the frames of a .blend
animation, as `bvhlab animate` exports them). Prints per animation and config: the share of
rebuilding's CPU time, the worst SAH ÷ a fresh build, the frames with a top rebuild, what ran.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import RESULTS  # noqa: E402

import bvhlab  # noqa: E402
from bvhlab.library.animations import ANIMATION_FRAMES, ANIMATIONS  # noqa: E402

REFIT_GRID = 708  # 2 * 708^2 = 1,002,528 triangles


def grid_wave(phase: float) -> np.ndarray:
    """refit_peers.cpp's mesh: z = 0.05 sin(20x + phase) cos(14y) over the unit square."""
    u = np.arange(REFIT_GRID + 1, dtype=np.float32) / np.float32(REFIT_GRID)
    x, y = np.meshgrid(u, u, indexing="ij")
    z = np.float32(0.05) * np.sin(np.float32(20) * x + np.float32(phase)) * np.cos(np.float32(14) * y)
    p = np.stack([x, y, z.astype(np.float32)], -1)
    a, b, c, d = p[:-1, :-1], p[1:, :-1], p[:-1, 1:], p[1:, 1:]
    return np.ascontiguousarray(np.stack([np.stack([a, b, c], -2), np.stack([b, d, c], -2)], 2).reshape(-1, 3, 3))


def refit_against_rebuild(repeat: int) -> dict:
    rest, moved = grid_wave(0.0), grid_wave(1.0)
    tree = bvhlab.build(rest, threads=1)
    tree.refit(moved)  # first touches of the versions' memory
    refit, rebuild = [], []
    for _ in range(repeat):  # interleaved: the machine's speed drifts
        t = time.perf_counter()
        tree.refit(moved)
        refit.append(time.perf_counter() - t)
        t = time.perf_counter()
        bvhlab.build(moved, threads=1)
        rebuild.append(time.perf_counter() - t)
    r, b = min(refit) * 1e3, min(rebuild) * 1e3
    return {"triangles": len(rest), "refit_ms": r, "rebuild_ms": b, "ratio": b / r}


def policies_over(animation: str, frames: int) -> dict:
    frame = ANIMATIONS[animation][0]()
    geometry = [frame(k / (frames - 1)) for k in range(frames)]
    trees = {policy: bvhlab.build(geometry[0], threads=1) for policy in bvhlab.UPDATE_POLICIES}
    rows = []
    for k, tris in enumerate(geometry[1:], start=1):
        fresh = bvhlab.build(tris, threads=1).stats["sah_cost"]
        row: dict = {"frame": k, "fresh_sah": fresh}
        for policy, tree in trees.items():
            s = tree.update(tris, policy=policy)
            row[policy] = {"ms": s.ms, "sah": s.sah_cost, "ran": s.policy, "subtrees": s.subtrees_rebuilt,
                           "primitives": s.primitives_rebuilt, "top_boxes": s.top_boxes}  # fmt: skip
        rows.append(row)
    print(animation)
    print(f"{'frame':>5} {'fresh SAH':>9} " + " ".join(f"{p + ' ms/SAH':>24}" for p in bvhlab.UPDATE_POLICIES))
    for r in rows:
        cells = " ".join(
            f"{r[p]['ms']:7.1f} {r[p]['sah'] / r['fresh_sah']:6.3f} {r[p]['ran'][:8]:>9}"
            for p in bvhlab.UPDATE_POLICIES
        )
        print(f"{r['frame']:>5} {r['fresh_sah']:9.2f} {cells}")
    totals = {p: sum(r[p]["ms"] for r in rows) for p in bvhlab.UPDATE_POLICIES}
    share = {p: totals[p] / totals["rebuild"] for p in bvhlab.UPDATE_POLICIES}
    worst = {p: max(r[p]["sah"] / r["fresh_sah"] for r in rows) for p in bvhlab.UPDATE_POLICIES}
    print("total ms:", {p: round(v, 1) for p, v in totals.items()})
    print("share of rebuilding every frame:", {p: round(v, 3) for p, v in share.items()})
    print("worst SAH / fresh:", {p: round(v, 3) for p, v in worst.items()})
    return {"triangles": len(geometry[0]), "frames": frames, "rows": rows, "total_ms": totals,
            "share_of_rebuild": share, "worst_sah_ratio": worst}  # fmt: skip


def frames_of(name: str, frames: int) -> list[np.ndarray]:
    if name.endswith(".npz"):
        z = np.load(name)
        return [z[k] for k in sorted(z.files, key=lambda s: int(s[1:]))]
    frame = ANIMATIONS[name][0]()
    return [frame(k / (frames - 1)) for k in range(frames)]


def interleaved(name: str, frames: int, configs: dict) -> None:
    """Adaptive (each config its own tree) against rebuilding every frame, thread CPU time."""
    geometry = frames_of(name, frames)
    fresh = [bvhlab.build(t, threads=1).stats["sah_cost"] for t in geometry[1:]]
    trees = {label: bvhlab.build(geometry[0], threads=1) for label in ["rebuild", *configs]}
    cpu = dict.fromkeys(trees, 0.0)
    worst, mean, tops = dict.fromkeys(trees, 0.0), dict.fromkeys(trees, 0.0), dict.fromkeys(trees, 0)
    ran: dict = {label: {} for label in trees}
    for k, tris in enumerate(geometry[1:]):
        for label, tree in trees.items():
            settings = {"policy": "rebuild"} if label == "rebuild" else {**configs[label], "policy": "adaptive"}
            t = time.thread_time()
            s = tree.update(tris, **settings)
            cpu[label] += time.thread_time() - t
            worst[label] = max(worst[label], s.sah_cost / fresh[k])
            mean[label] += s.sah_cost / fresh[k] / len(fresh)
            tops[label] += s.top_boxes > 0
            ran[label][s.policy] = ran[label].get(s.policy, 0) + 1
    for label in configs:
        print(f"{Path(name).name:14s} {label:12s} share of rebuilding {cpu[label] / cpu['rebuild']:.3f} "
              f"worst SAH / fresh {worst[label]:.3f} mean {mean[label]:.4f} "
              f"tops {tops[label]:2d} ran {ran[label]}", flush=True)  # fmt: skip


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__)
    p.add_argument("--json", action="store_true")
    p.add_argument("--frames", type=int, default=ANIMATION_FRAMES)
    p.add_argument("--repeat", type=int, default=7)
    p.add_argument("--interleaved", default="", help="animations (wave, crowd, FRAMES.npz), comma-separated")
    p.add_argument("--configs", default='{"defaults": {}}', help="adaptive settings by label, JSON")
    args = p.parse_args()
    if args.interleaved:
        for name in args.interleaved.split(","):
            interleaved(name, args.frames, json.loads(args.configs))
        return
    refit = refit_against_rebuild(args.repeat)
    print(
        f"refit of {refit['triangles']:,} triangles: {refit['refit_ms']:.1f} ms, rebuild {refit['rebuild_ms']:.1f} ms: "
        f"{refit['ratio']:.1f}x"
    )
    animations = {name: policies_over(name, args.frames) for name in ("wave", "crowd")}
    if args.json:
        out = {"note": "one run, one core; the 2-core machine is shared with other jobs", "refit": refit,
               **animations}  # fmt: skip
        (RESULTS / "updates.json").write_text(json.dumps(out, indent=1) + "\n")


if __name__ == "__main__":
    main()
