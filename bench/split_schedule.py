"""What a different split rule at the top of the tree would do to the SAH, without changing the
builder: the ranges above `--cut` primitives are split in Python (binned SAH over the node's box
with `--top` buckets, or `sweep`: the exact SAH over sorted centroids), and each range of at most
`--cut` is built by bvhlab with the settings of `--below` (JSON, e.g. '{"bins": 32}'). The tree's
cost in sah_cost's convention composes exactly: Σ A(top inner node) / A(root) + Σ sah_cost(range's
tree) · A(range) / A(root) (a range's tree's root box is its primitives' box, as in one build).
With `--top 12 --below '{}'` it gives the default build's SAH on the bench scenes (to the 3 decimals printed; Python
splits in float64 where the builder bins in float32, so a near tie may fall differently).
Slow (numpy): minutes per scene at 1M triangles.

    python bench/split_schedule.py --scenes repeat1m,room1m --cut 1024 --top 12 --below '{"bins": 32}'
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _peers  # noqa: E402


def half_area(lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    e = np.maximum(hi - lo, 0.0)
    return e[..., 0] * e[..., 1] + e[..., 1] * e[..., 2] + e[..., 2] * e[..., 0]


def prefix_suffix(lo: np.ndarray, hi: np.ndarray):
    """Boxes of [0, j] and of [j + 1, end) for each j (rows in order)."""
    plo, phi = np.minimum.accumulate(lo, 0), np.maximum.accumulate(hi, 0)
    slo, shi = np.minimum.accumulate(lo[::-1], 0)[::-1], np.maximum.accumulate(hi[::-1], 0)[::-1]
    return half_area(plo[:-1], phi[:-1]), half_area(slo[1:], shi[1:])


def binned(lo, hi, c2, box_lo, box_hi, bins: int):
    """The cheapest bucket boundary (cost, left mask): bvhlab's default rule (binning.h)."""
    best, n = (np.inf, None), len(c2)
    for a in range(3):
        extent = box_hi[a] - box_lo[a]
        if extent <= 0:
            continue
        k = np.clip(((c2[:, a] - 2 * box_lo[a]) * (bins / (2 * extent))).astype(np.int64), 0, bins - 1)
        bucket_lo, bucket_hi = np.full((bins, 3), np.inf), np.full((bins, 3), -np.inf)
        np.minimum.at(bucket_lo, k, lo), np.maximum.at(bucket_hi, k, hi)
        left = np.cumsum(np.bincount(k, minlength=bins))[:-1]
        area_left, area_right = prefix_suffix(bucket_lo, bucket_hi)
        ok = (left > 0) & (left < n)
        cost = np.where(ok, area_left * left + area_right * (n - left), np.inf)
        j = int(np.argmin(cost))
        if cost[j] < best[0]:
            best = (cost[j], k <= j)
    return best


def sweep(lo, hi, c2, box_lo, box_hi, bins: int):
    """The exact SAH: every position of the centroids sorted on each axis."""
    best, n = (np.inf, None), len(c2)
    for a in range(3):
        order = np.argsort(c2[:, a], kind="stable")
        area_left, area_right = prefix_suffix(lo[order], hi[order])
        left = np.arange(1, n)
        cost = area_left * left + area_right * (n - left)
        j = int(np.argmin(cost))
        if cost[j] < best[0]:
            mask = np.zeros(n, bool)
            mask[order[: j + 1]] = True
            best = (cost[j], mask)
    return best


def composed_sah(tris: np.ndarray, cut: int, top: str, below: dict) -> tuple[float, int]:
    import bvhlab

    lo_all, hi_all = tris.min(1).astype(np.float64), tris.max(1).astype(np.float64)
    c2_all = lo_all + hi_all
    root = half_area(lo_all.min(0), hi_all.max(0))
    split = sweep if top == "sweep" else binned
    bins = 0 if top == "sweep" else int(top)
    total, ranges, stack = 0.0, 0, [np.arange(len(tris))]
    while stack:
        idx = stack.pop()
        lo, hi = lo_all[idx], hi_all[idx]
        box_lo, box_hi = lo.min(0), hi.max(0)
        share = half_area(box_lo, box_hi) / root
        if len(idx) <= cut:
            total += float(bvhlab.build(tris[idx], threads=1, **below).stats["sah_cost"]) * share
            ranges += 1
            continue
        total += share
        _, left = split(lo, hi, c2_all[idx], box_lo, box_hi, bins)
        stack += [idx[left], idx[~left]]
    return total, ranges


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scenes", default="repeat1m")
    ap.add_argument("--cut", type=int, default=65536, help="ranges of at most this many are built by bvhlab")
    ap.add_argument("--top", default="12", help="buckets above the cut, or 'sweep'")
    ap.add_argument("--below", default="{}", help="bvhlab.build settings at and below the cut (JSON)")
    args = ap.parse_args()
    below = json.loads(args.below)
    for name, tris in _peers.scenes(args.scenes.split(",")).items():
        start = time.perf_counter()
        sah, ranges = composed_sah(tris, args.cut, args.top, below)
        took = time.perf_counter() - start
        print(f"{name}: cut {args.cut}, top {args.top}, below {below}: SAH {sah:.3f} ({ranges} ranges, {took:.0f} s)")


if __name__ == "__main__":
    main()
