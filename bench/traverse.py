"""Traversal benchmark: single rays on one core, bvhlab's traversals (8-wide, stack, stackless)
beside Embree 3 (C++ rtcIntersect1 / rtcOccluded1, MEDIUM) and tinybvh's BVH8_CPU and BVH4_CPU
(Intersect / IsOccluded; Build, BuildHQ and Optimize; when a local copy is given), on the same
rays in the same process, interleaved and repeated.

    python bench/traverse.py [--scenes sponza,room1m,uniform1m] [--repeat 5] [--rounds 2]
                             [--callgrind 20000] [--tinybvh DIR] [--peers SPEC,...] [--cpu-time]

For each scene: random rays (origins in the bounds, uniform directions, 200k) and primary rays
(640×480; on Sponza the report's Figure 6 view), closest hit; and shadow rays (any hit: bvhlab's
occluded) from the random rays' hits to a point light (_peers.shadow_rays). Prints Mrays/s with
ratios against Embree MEDIUM and against the fastest peer (not bvhlab), the hits each system found
(shadow rays: those occluded) and how many rays disagree with Embree's hit distance (or
occlusion), and callgrind instructions per ray (on `--callgrind` rays spread over the set); writes
bench/results/traverse.json. Each bvhlab row names its build settings and traversal; the rows
but "batch" call the single-ray functions (intersect_wide, occluded_wide) in a loop, as the peers
are called; the batch row calls the batch entry point that Bvh.intersect and Bvh.occluded call
(rays checked and scaled, each chunk traced grouped by ray octant). `--peers`
keeps only the given specs (Embree MEDIUM is always kept: the others are compared with it).
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _common  # noqa: E402
import _peers  # noqa: E402

PEERS = [  # (label, bvh_bench spec); Embree MEDIUM first: the others are compared with it
    ("Embree 3 MEDIUM rtcIntersect1 / rtcOccluded1", "embree:medium"),
    ("bvhlab wide (default tree)", "bvhlab:"),
    (
        "bvhlab wide, batch: Bvh.intersect / Bvh.occluded's entry point (intersect_batch, one thread)",
        "bvhlab:batch=1",
    ),
    ("bvhlab wide (default tree, optimised: 25 batches of reinsertion, Bvh.optimize)", "bvhlab:opt=25"),
    ("bvhlab stack (default tree)", "bvhlab:query=stack"),
    ("bvhlab stackless (default tree)", "bvhlab:query=stackless"),
    ("bvhlab wide (default tree but primitives counted one by one: sah_block 1)", "bvhlab:block=1"),
    (
        "bvhlab wide (report's tree: sah12, largest, leaf 1)",
        "bvhlab:method=sah,bins=12,axis=largest,leaf=1,span=centroids,block=1",
    ),
    ("bvhlab wide (SBVH tree: method sbvh)", "bvhlab:method=sbvh"),
    ("tinybvh BVH8_CPU", "tinybvh:"),
    ("tinybvh BVH4_CPU", "tinybvh:bvh4"),
    ("tinybvh BuildHQ / BVH8_CPU", "tinybvh:hq"),
    ("tinybvh Build + Optimize / BVH8_CPU", "tinybvh:opt"),
]


def measure(
    exe: Path, mesh: Path, rays: dict[str, Path], repeat: int, rounds: int, peers: list, clock: str = "seconds"
) -> dict:
    """Times of each peer on each ray set; `clock` "seconds" (wall) or "cpu_seconds" (the tracing
    thread's CPU time, which a loaded machine disturbs far less)."""
    args = ["trace", str(mesh), *(a for name, path in rays.items() for a in _peers.ray_args(name, path))]
    args += [a for _, s in peers for a in ("--peer", s)]
    args += ["--repeat", str(repeat)]
    out = {name: {} for name in rays}
    for _ in range(rounds):
        result = _peers.run(exe, args, 1)
        for name, ray_set in zip(rays, result["ray_sets"]):
            for p in ray_set["peers"]:
                row = out[name].setdefault(p["spec"], {"spec": p["spec"], "seconds": [], "count": ray_set["count"]})
                row["seconds"].extend(p[clock])
                row.update(hits=p["hits"], disagree_with_embree=p["disagree_with_first"])
    for name in out:
        for label, spec in peers:
            out[name][spec]["label"] = label
    return out


def count_instructions(exe: Path, mesh: Path, rays: dict[str, Path], sample: int, result: dict) -> None:
    """Callgrind on `sample` rays spread evenly over each set: the first rows of a camera's image
    can all miss the scene (room1m and uniform1m counted the same empty rows before)."""
    import numpy as np

    for name, path in rays.items():
        few = path.with_suffix(".few.f32")
        all_rays = np.fromfile(path, np.float32).reshape(-1, 7 if name == "shadow" else 6)
        subset = all_rays[:: max(1, len(all_rays) // sample)][:sample]
        np.ascontiguousarray(subset).tofile(few)
        for spec, row in result[name].items():
            n = _peers.instructions(exe, [str(mesh), *_peers.ray_args(name, few), "--peer", spec])
            row["instructions_per_ray"] = n / len(subset) if n else None
            print(f"  callgrind {name} {row['label']}: {n}", file=sys.stderr, flush=True)


def report(scene: str, triangles: int, result: dict) -> None:
    for name, rows in result.items():
        embree = _peers.median(rows["embree:medium"]["seconds"])
        best_peer = min(_peers.median(r["seconds"]) for spec, r in rows.items() if not spec.startswith("bvhlab"))
        table = []
        for row in rows.values():
            t = _peers.median(row["seconds"])
            row["mrays_per_s"] = row["count"] / t / 1e6
            row["x_best_peer"] = best_peer / t
            ipr = row.get("instructions_per_ray")
            table.append(
                [
                    row["label"],
                    row["mrays_per_s"],
                    embree / t,
                    best_peer / t,
                    row["hits"],
                    row["disagree_with_embree"],
                    round(ipr) if ipr else "",
                ]
            )
        what = "shadow rays (any hit)" if name == "shadow" else f"{name} rays"
        _common.print_table(
            ["traversal", "Mrays/s", "x Embree", "x best peer", "hits", "disagree", "instr/ray"],
            table,
            title=f"\n{scene} ({triangles} triangles), {what}, 1 thread",
        )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scenes", default="sponza,room1m,uniform1m")
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--rounds", type=int, default=2)
    ap.add_argument(
        "--callgrind", type=int, default=20000, help="rays callgrind counts, spread over each set (0: none)"
    )
    ap.add_argument("--tinybvh", default=os.environ.get("BVHLAB_TINYBVH_DIR"))
    ap.add_argument("--peers", help="comma-separated bvh_bench specs to keep (default: all; _peers.split_specs)")
    ap.add_argument("--json", default="traverse.json", help="results file name in bench/results (or a path)")
    ap.add_argument(
        "--cpu-time",
        action="store_true",
        help="time by the tracing thread's CPU time rather than wall time (for a loaded machine)",
    )
    args = ap.parse_args()
    exe = _peers.build_bvh_bench(args.tinybvh)
    peers = [(label, spec) for label, spec in PEERS if args.tinybvh or not spec.startswith("tinybvh")]
    _common.json_path(args.json)  # a bad folder fails now, not after the run
    if args.peers:
        # Embree MEDIUM always first: the others are compared with it
        chosen = [row for row in _peers.chosen_rows(args.peers, peers, args.tinybvh) if row[1] != "embree:medium"]
        peers = [row for row in peers if row[1] == "embree:medium"] + chosen
    results = {"machine": _common.machine(), "scenes": {}}
    print(_common.machine_line(results["machine"]), file=sys.stderr, flush=True)
    with tempfile.TemporaryDirectory() as tmp:
        for scene, tris in _peers.scenes(args.scenes.split(",")).items():
            mesh, rays = _peers.write_inputs(Path(tmp), scene, tris)
            print(f"{scene}: tracing", file=sys.stderr, flush=True)
            clock = "cpu_seconds" if args.cpu_time else "seconds"
            result = measure(exe, mesh, rays, args.repeat, args.rounds, peers, clock)
            if args.callgrind:
                count_instructions(exe, mesh, rays, args.callgrind, result)
            results["scenes"][scene] = {"triangles": len(tris), "rays": result}
            report(scene, len(tris), result)
    print(f"\nwrote {_common.write_json(args.json, results)}")


if __name__ == "__main__":
    main()
