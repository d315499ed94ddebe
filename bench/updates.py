"""Update policies over an animation (issue 34): a wave travelling over a 250K-triangle grid
(plus a bump that sweeps across it, so that parts of the tree go bad), 12 frames, one core.
Per frame and policy: update ms, the policy adaptive chose, SAH cost, and a fresh build's SAH
cost and ms. Prints a table; `--json` writes bench/results/updates.json.

    .venv/bin/python bench/updates.py [--json]
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

GRID = 354  # 2 * 354^2 = 250,632 triangles


def frame(t: float) -> np.ndarray:
    u = np.linspace(0.0, 1.0, GRID + 1, dtype=np.float64)
    x, y = np.meshgrid(u, u, indexing="ij")
    bump_x = 0.1 + 0.8 * t  # a tall bump sweeping along x
    z = 0.03 * np.sin(20 * x + 6 * t) + 0.4 * np.exp(-((x - bump_x) ** 2 + (y - 0.5) ** 2) / 0.005)
    p = np.stack([x, y, z], -1).astype(np.float32)
    a, b, c, d = p[:-1, :-1], p[1:, :-1], p[:-1, 1:], p[1:, 1:]
    tris = np.concatenate([np.stack([a, b, c], -2), np.stack([b, d, c], -2)]).reshape(-1, 3, 3)
    return np.ascontiguousarray(tris)


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__)
    p.add_argument("--json", action="store_true")
    p.add_argument("--frames", type=int, default=12)
    args = p.parse_args()
    frames = [frame(k / (args.frames - 1)) for k in range(args.frames)]
    trees = {policy: bvhlab.build(frames[0], threads=1) for policy in bvhlab.UPDATE_POLICIES}
    rows = []
    for k, tris in enumerate(frames[1:], start=1):
        t = time.perf_counter()
        fresh = bvhlab.build(tris, threads=1)
        row = {"frame": k, "fresh_ms": (time.perf_counter() - t) * 1e3, "fresh_sah": fresh.stats["sah_cost"]}
        for policy, tree in trees.items():
            s = tree.update(tris, policy=policy)
            row[policy] = {"ms": s.ms, "sah": s.sah_cost, "ran": s.policy, "subtrees": s.subtrees_rebuilt}
        rows.append(row)
    print(f"{'frame':>5} {'fresh SAH':>9} " + " ".join(f"{p + ' ms/SAH':>22}" for p in bvhlab.UPDATE_POLICIES))
    for r in rows:
        cells = " ".join(f"{r[p]['ms']:8.1f} {r[p]['sah']:6.1f} {r[p]['ran'][:7]:>7}" for p in bvhlab.UPDATE_POLICIES)
        print(f"{r['frame']:>5} {r['fresh_sah']:9.1f} {cells}")
    totals = {p: sum(r[p]["ms"] for r in rows) for p in bvhlab.UPDATE_POLICIES}
    worst = {p: max(r[p]["sah"] / r["fresh_sah"] for r in rows) for p in bvhlab.UPDATE_POLICIES}
    print("total ms:", {p: round(v, 1) for p, v in totals.items()})
    print("worst SAH / fresh:", {p: round(v, 3) for p, v in worst.items()})
    if args.json:
        out = {"triangles": len(frames[0]), "frames": rows, "total_ms": totals, "worst_sah_ratio": worst}
        (RESULTS / "updates.json").write_text(json.dumps(out, indent=1) + "\n")


if __name__ == "__main__":
    main()
