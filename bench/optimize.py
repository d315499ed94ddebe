"""Optimisation after the build (Bvh.optimize, issue 36): the SAH cost of the default tree before
and after 5, 10, 25 (the default) and 100 batches of reinsertion, the optimisation's time on one
core, and what the optimised tree gains in ray time (bvh_bench, single rays through the wide
tree, random and primary rays as bench/traverse.py shoots them, one core, the default and the
optimised tree interleaved in one process with Embree MEDIUM and, given --tinybvh, tinybvh's
BVH8_CPU beside them).

    python bench/optimize.py [--scenes sponza] [--batches 5,10,25,100] [--repeat 5] [--rounds 2]
                             [--callgrind 20000] [--tinybvh DIR]

Also callgrind's instructions per ray (on `--callgrind` rays spread over each set), which the
machine's load does not change. Writes bench/results/optimize.json.
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
from traverse import count_instructions, measure  # noqa: E402

import bvhlab  # noqa: E402


def sah_rows(tris, batches: list[int]) -> list[dict]:
    """The default tree (one thread) optimised for each number of batches, one core."""
    rows = []
    for n in batches:
        tree = bvhlab.build(tris, threads=1)
        s = tree.optimize(iterations=n)
        rows.append({"batches": n, **{k: getattr(s, k) for k in s.__dataclass_fields__}})
        print(
            f"  {n:>4} batches: SAH {s.sah_before:.3f} -> {s.sah_after:.3f} "
            f"({100 * (1 - s.sah_after / s.sah_before):.1f}% lower) in {s.ms:.0f} ms",
            file=sys.stderr,
            flush=True,
        )
    return rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scenes", default="sponza")
    ap.add_argument("--batches", default="5,10,25,100")
    ap.add_argument("--ray-batches", type=int, default=25, help="batches of the optimised tree that is traced")
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--rounds", type=int, default=2)
    ap.add_argument(
        "--callgrind", type=int, default=20000, help="rays callgrind counts, spread over each set (0: none)"
    )
    ap.add_argument("--tinybvh", default=os.environ.get("BVHLAB_TINYBVH_DIR"))
    args = ap.parse_args()
    exe = _peers.build_bvh_bench(args.tinybvh)
    _common.pin_to_cores(1)  # the optimisations' times: one core
    peers = [
        ("Embree 3 MEDIUM rtcIntersect1", "embree:medium"),
        ("bvhlab wide (default tree)", "bvhlab:"),
        (f"bvhlab wide (default tree optimised, {args.ray_batches} batches)", f"bvhlab:opt={args.ray_batches}"),
    ]
    if args.tinybvh:
        peers.append(("tinybvh BVH8_CPU", "tinybvh:"))
    results = {"machine": _common.machine(), "scenes": {}}
    with tempfile.TemporaryDirectory() as tmp:
        for scene, tris in _peers.scenes(args.scenes.split(",")).items():
            print(f"{scene}: optimising", file=sys.stderr, flush=True)
            sah = sah_rows(tris, [int(b) for b in args.batches.split(",")])
            mesh, rays = _peers.write_inputs(Path(tmp), scene, tris)
            print(f"{scene}: tracing", file=sys.stderr, flush=True)
            traced = measure(exe, mesh, rays, args.repeat, args.rounds, peers)
            if args.callgrind:  # instructions per ray: what the machine's load does not change
                count_instructions(exe, mesh, rays, args.callgrind, traced)
            table = []
            for name, rows in traced.items():
                base = _peers.median(rows["bvhlab:"]["seconds"])
                for row in rows.values():
                    t = _peers.median(row["seconds"])
                    row["mrays_per_s"] = row["count"] / t / 1e6
                    ipr = row.get("instructions_per_ray")
                    table.append(
                        [name, row["label"], row["mrays_per_s"], base / t, row["hits"], round(ipr) if ipr else ""]
                    )
            _common.print_table(
                ["rays", "tree", "Mrays/s", "x default tree", "hits", "instr/ray"],
                table,
                title=f"\n{scene} ({len(tris)} triangles), 1 core",
            )
            results["scenes"][scene] = {"triangles": len(tris), "optimize": sah, "rays": traced}
    print(f"\nwrote {_common.write_json('optimize.json', results)}")


if __name__ == "__main__":
    main()
