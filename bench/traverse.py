"""Traversal benchmark: single-ray closest hit on one core, bvhlab's 8-wide traversal beside
Embree 3 (C++ rtcIntersect1, MEDIUM) and tinybvh's BVH8_CPU (when a local copy is given), on the
same rays in the same process, interleaved and repeated.

    python bench/traverse.py [--scenes sponza,room1m,uniform1m] [--repeat 5] [--rounds 2]
                             [--callgrind 20000] [--tinybvh DIR]

For each scene: random rays (origins in the bounds, uniform directions, 200k) and primary rays
(640×480; on Sponza the report's Figure 6 view). Prints Mrays/s with ratios
against Embree MEDIUM, the hits each system found and how many rays disagree with Embree's hit
distance, and callgrind instructions per ray (on `--callgrind` rays spread over the set); writes
bench/results/traverse.json. Each bvhlab row names its build settings.
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
    ("Embree 3 MEDIUM rtcIntersect1", "embree:medium"),
    ("bvhlab wide (default tree)", "bvhlab:"),
    ("bvhlab wide (default tree, optimised: 25 batches of reinsertion, Bvh.optimize)", "bvhlab:opt=25"),
    ("bvhlab wide (default tree but primitives counted one by one: sah_block 1)", "bvhlab:block=1"),
    (
        "bvhlab wide (report's tree: sah12, largest, leaf 1)",
        "bvhlab:method=sah,bins=12,axis=largest,leaf=1,span=centroids,block=1",
    ),
    ("tinybvh BVH8_CPU", "tinybvh:"),
]


def measure(exe: Path, mesh: Path, rays: dict[str, Path], repeat: int, rounds: int, peers: list) -> dict:
    args = ["trace", str(mesh), *map(str, rays.values())] + [a for _, s in peers for a in ("--peer", s)]
    args += ["--repeat", str(repeat)]
    out = {name: {} for name in rays}
    for _ in range(rounds):
        result = _peers.run(exe, args, 1)
        for name, ray_set in zip(rays, result["ray_sets"]):
            for p in ray_set["peers"]:
                row = out[name].setdefault(p["spec"], {"spec": p["spec"], "seconds": [], "count": ray_set["count"]})
                row["seconds"].extend(p["seconds"])
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
        all_rays = np.fromfile(path, np.float32).reshape(-1, 6)
        subset = all_rays[:: max(1, len(all_rays) // sample)][:sample]
        np.ascontiguousarray(subset).tofile(few)
        for spec, row in result[name].items():
            n = _peers.instructions(exe, [str(mesh), str(few), "--peer", spec])
            row["instructions_per_ray"] = n / len(subset) if n else None
            print(f"  callgrind {name} {row['label']}: {n}", file=sys.stderr, flush=True)


def report(scene: str, triangles: int, result: dict) -> None:
    for name, rows in result.items():
        embree = _peers.median(rows["embree:medium"]["seconds"])
        table = []
        for row in rows.values():
            t = _peers.median(row["seconds"])
            ipr = row.get("instructions_per_ray")
            table.append(
                [
                    row["label"],
                    row["count"] / t / 1e6,
                    embree / t,
                    row["hits"],
                    row["disagree_with_embree"],
                    round(ipr) if ipr else "",
                ]
            )
        _common.print_table(
            ["traversal", "Mrays/s", "x Embree", "hits", "disagree", "instr/ray"],
            table,
            title=f"\n{scene} ({triangles} triangles), {name} rays, 1 thread",
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
    args = ap.parse_args()
    exe = _peers.build_bvh_bench(args.tinybvh)
    peers = [(label, spec) for label, spec in PEERS if args.tinybvh or not spec.startswith("tinybvh")]
    results = {"machine": _common.machine(), "scenes": {}}
    with tempfile.TemporaryDirectory() as tmp:
        for scene, tris in _peers.scenes(args.scenes.split(",")).items():
            mesh = Path(tmp) / f"{scene}.f32"
            tris.tofile(mesh)
            rays = {}
            for name, r in _peers.rays_for(scene, tris).items():
                rays[name] = Path(tmp) / f"{scene}_{name}.f32"
                r.tofile(rays[name])
            print(f"{scene}: tracing", file=sys.stderr, flush=True)
            result = measure(exe, mesh, rays, args.repeat, args.rounds, peers)
            if args.callgrind:
                count_instructions(exe, mesh, rays, args.callgrind, result)
            results["scenes"][scene] = {"triangles": len(tris), "rays": result}
            report(scene, len(tris), result)
    print(f"\nwrote {_common.write_json('traverse.json', results)}")


if __name__ == "__main__":
    main()
