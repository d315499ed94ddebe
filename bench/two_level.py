"""Two-level walks against flat trees (issue 34): rays on one core through an instanced scene's
TLAS and BLASes (bvhlab wide, stack, stackless, one ray at a time, and wide through the batch
queries, which reorder incoherent rays; Embree 3's instances) beside one flat tree
over the same triangles moved into the world (bvhlab wide, Embree 3 MEDIUM), interleaved in one
process (bench/cpp/tlas_bench), and callgrind instructions per ray.

    python bench/two_level.py [--scenes mover,many,hundred] [--repeat 5] [--rounds 2]
                              [--callgrind 20000] [--peers SPEC,...] [--json two_level.json]

Scenes: `mover` (a static 240K knot and a floor in mesh 0, one identity instance, and a 968-
triangle knot as a second instance moved away: the layout of a scene with one moving object,
python/bvhlab/blender/motion.py), `one` (the mover's mesh 0 alone, one identity instance: the
flat query's own path), `many` (10,000 instances of a 480-triangle knot, rotated and scaled),
`hundred` (100 instances of a 15K knot, bench/instancing.py's). Rays: random (200K,
origins in the bounds, uniform directions; closest hit) and shadow (any hit, to a point light
from the random rays' hits, _peers.shadow_rays). Prints ms per set, each row ÷ the flat bvhlab wide
walk, and instructions per ray; writes bench/results/two_level.json.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _common  # noqa: E402
import _peers  # noqa: E402
from instancing import _placements  # noqa: E402

PEERS = [  # the first is what the others are compared with
    ("bvhlab flat wide", "flat/bvhlab:"),
    ("bvhlab two-level wide", "two/bvhlab"),
    ("bvhlab two-level wide, batch (one thread)", "two/bvhlab:batch=1"),
    ("bvhlab flat stack", "flat/bvhlab:query=stack"),
    ("bvhlab two-level stack", "two/bvhlab:query=stack"),
    ("bvhlab flat stackless", "flat/bvhlab:query=stackless"),
    ("bvhlab two-level stackless", "two/bvhlab:query=stackless"),
    ("Embree 3 flat MEDIUM", "flat/embree:medium"),
    ("Embree 3 two-level (instances)", "two/embree"),
]


def scene(name: str) -> tuple[list[np.ndarray], np.ndarray]:
    """Meshes (T,3,3) and instances (N,13: mesh index, 3×4 object-to-world) of a bench scene."""
    from bvhlab.library import procedural

    if name in ("mover", "one"):
        big = procedural.torus_knot(240_000)
        floor = np.array([[[-8, -8, -1.5], [8, -8, -1.5], [8, 8, -1.5]], [[-8, -8, -1.5], [8, 8, -1.5], [-8, 8, -1.5]]])
        small = procedural.torus_knot(968, scale=0.4)
        meshes = [np.concatenate([big, floor.astype(np.float32)]), small]
        placed = np.zeros((2, 3, 4), np.float32)
        placed[:, :, :3] = np.eye(3)
        placed[1, :, 3] = (2.5, -2.0, 0.5)
        mesh_of = np.array([0, 1])
        if name == "one":  # the mover's static mesh alone, one identity instance: the flat query's own path
            meshes, placed, mesh_of = meshes[:1], placed[:1], mesh_of[:1]
    elif name == "many":
        meshes, placed = [procedural.torus_knot(480)], _placements(10_000, 7)
        mesh_of = np.zeros(10_000)
    elif name == "hundred":
        meshes, placed = [procedural.torus_knot(15_000)], _placements(100, 7)
        mesh_of = np.zeros(100)
    else:
        raise SystemExit(f"bench: unknown scene {name}")
    rows = np.concatenate([mesh_of[:, None], placed.reshape(-1, 12)], 1)
    return [np.ascontiguousarray(m, np.float32) for m in meshes], np.ascontiguousarray(rows, np.float32)


def flattened(meshes: list[np.ndarray], instances: np.ndarray) -> np.ndarray:
    parts = []
    for row in instances:
        m = row[1:].reshape(3, 4)
        parts.append(meshes[int(row[0])] @ m[:, :3].T + m[:, 3])
    return np.concatenate(parts).astype(np.float32)


def write_inputs(folder: Path, name: str) -> tuple[list[str], dict[str, Path]]:
    """tlas_bench's scene arguments and ray files of a scene."""
    from bvhlab.library import procedural

    meshes, instances = scene(name)
    args = []
    for k, m in enumerate(meshes):
        m.tofile(folder / f"{name}_mesh{k}.f32")
        args += ["--mesh", str(folder / f"{name}_mesh{k}.f32")]
    instances.tofile(folder / f"{name}_instances.f32")
    args += ["--instances", str(folder / f"{name}_instances.f32")]
    world = flattened(meshes, instances)
    o, d = procedural.random_rays(world, 200_000, seed=3)
    random = np.ascontiguousarray(np.concatenate([o, d], 1), np.float32)
    rays = {"random": random, "shadow": _peers.shadow_rays(world, random, 2)}
    paths = {}
    for set_name, r in rays.items():
        paths[set_name] = folder / f"{name}_{set_name}.f32"
        r.tofile(paths[set_name])
    return args, paths


def measure(exe, scene_args, rays, repeat, rounds, peers, sample) -> dict:
    out = {name: {spec: {"label": label, "seconds": []} for label, spec in peers} for name in rays}
    args = ["trace", *scene_args, *(a for n, p in rays.items() for a in _peers.ray_args(n, p))]
    args += [a for _, s in peers for a in ("--peer", s)] + ["--repeat", str(repeat)]
    for _ in range(rounds):
        result = _peers.run(exe, args, 1)
        for name, ray_set in zip(rays, result["ray_sets"]):
            for p in ray_set["peers"]:
                row = out[name][p["spec"]]
                row["seconds"].extend(p["seconds"])
                row.update(count=ray_set["count"], hits=p["hits"], disagree=p["disagree_with_first"])
    if sample:
        for name, path in rays.items():
            few = path.with_suffix(".few.f32")
            all_rays = np.fromfile(path, np.float32).reshape(-1, 7 if name == "shadow" else 6)
            subset = all_rays[:: max(1, len(all_rays) // sample)][:sample]
            np.ascontiguousarray(subset).tofile(few)
            for spec, row in out[name].items():
                n = _peers.instructions(exe, [*scene_args, *_peers.ray_args(name, few), "--peer", spec])
                row["instructions_per_ray"] = n / len(subset) if n else None
    return out


def report(name: str, result: dict) -> None:
    for set_name, rows in result.items():
        first = _peers.median(next(iter(rows.values()))["seconds"])
        table = []
        for row in rows.values():
            t = _peers.median(row["seconds"])
            row["ms"], row["x_flat_wide"] = t * 1e3, t / first
            ipr = row.get("instructions_per_ray")
            table.append(
                [row["label"], row["ms"], row["x_flat_wide"], row["hits"], row["disagree"], round(ipr) if ipr else ""]
            )
        _common.print_table(
            ["query", "ms", "time ÷ flat wide", "hits", "disagree", "instr/ray"],
            table,
            title=f"\n{name}, {set_name} rays, 1 thread",
        )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scenes", default="mover,many,hundred")
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--rounds", type=int, default=2)
    ap.add_argument("--callgrind", type=int, default=20_000, help="rays per set counted (0: none)")
    ap.add_argument("--peers", help="comma-separated specs to keep (default: all)")
    ap.add_argument("--json", default="two_level.json", help="results file name in bench/results (or a path)")
    args = ap.parse_args()
    _common.json_path(args.json)  # a bad folder fails now, not after the run
    peers = [p for p in PEERS if not args.peers or p[1] in args.peers.split(",")]
    exe = _peers.build_bvh_bench(None, "tlas_bench")
    results = {}
    with tempfile.TemporaryDirectory() as tmp:
        for name in args.scenes.split(","):
            scene_args, rays = write_inputs(Path(tmp), name)
            results[name] = measure(exe, scene_args, rays, args.repeat, args.rounds, peers, args.callgrind)
            report(name, results[name])
    _common.write_json(args.json, results)


if __name__ == "__main__":
    main()
