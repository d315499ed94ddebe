"""The bench binaries run on the inputs bench/*.py write, and their bvhlab peers agree (a ctest, with
the standard library only): bvh_bench over a small mesh (ray by ray and through the batch, closest
and any hit) and tlas_bench over instances of two meshes (the two-level walks one ray at a time and
through the batch, and the flat tree over the same triangles). A change to the files' layout that
bench/two_level.py's runs would meet (its instances once read as rows of triangles: every run
refused) fails here first.

    python3 bench/cpp/smoke.py BVH_BENCH TLAS_BENCH
"""

from __future__ import annotations

import json
import math
import random
import struct
import subprocess
import sys
import tempfile
from pathlib import Path


def write(path: Path, rows: list[list[float]]) -> Path:
    path.write_bytes(b"".join(struct.pack(f"{len(r)}f", *r) for r in rows))
    return path


def soup(rng: random.Random, count: int, size: float) -> list[list[float]]:
    """Small triangles in a cube of `size`."""
    rows = []
    for _ in range(count):
        c = [rng.uniform(0, size) for _ in range(3)]
        rows.append([c[a % 3] + rng.uniform(-0.3, 0.3) for a in range(9)])
    return rows


def rays(rng: random.Random, count: int, size: float, shadow: bool) -> list[list[float]]:
    out = []
    for _ in range(count):
        d = [rng.gauss(0, 1) for _ in range(3)]
        row = [rng.uniform(-1, size + 1) for _ in range(3)] + d
        out.append(row + [rng.uniform(0.5, size)] if shadow else row)
    return out


def run(exe: str, args: list[str]) -> dict:
    done = subprocess.run([exe, "trace", *args, "--repeat", "1"], capture_output=True, text=True)
    if done.returncode:
        sys.exit(f"{Path(exe).name} failed ({done.returncode}): {done.stderr.strip()}")
    return json.loads(done.stdout)


def check(result: dict, what: str) -> None:
    """Every peer answers every ray as the first does (hits at distances within 1e-4)."""
    sets = result["ray_sets"]
    assert len(sets) == 2, f"{what}: {len(sets)} ray sets"
    for ray_set in sets:
        counts = {p["spec"]: p["hits"] for p in ray_set["peers"]}
        assert 0 < min(counts.values()) < ray_set["count"], f"{what}: hits {counts} of {ray_set['count']}"
        for p in ray_set["peers"]:
            assert p["disagree_with_first"] == 0, f"{what}, {p['spec']}: {p['disagree_with_first']} rays differ"


def main() -> None:
    bvh_bench, tlas_bench = sys.argv[1:3]
    rng = random.Random(5)
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        ray_args = [str(write(folder / "rays.f32", rays(rng, 3000, 10, False)))]
        ray_args += ["--shadow", str(write(folder / "shadow.f32", rays(rng, 3000, 10, True)))]
        mesh = write(folder / "mesh.f32", soup(rng, 2000, 10))
        flat = ["bvhlab:", "bvhlab:batch=1", "bvhlab:query=stack"]
        check(run(bvh_bench, [str(mesh), *ray_args, *(a for p in flat for a in ("--peer", p))]), "bvh_bench")

        meshes = [write(folder / "m0.f32", soup(rng, 300, 1)), write(folder / "m1.f32", soup(rng, 50, 1))]
        instances = []
        for i in range(400):  # the mesh index and a 3×4 row-major transform: a rotation about z, a move
            a, s = rng.uniform(0, 2 * math.pi), rng.uniform(0.5, 1.5)
            move = [rng.uniform(0, 9) for _ in range(3)]
            c, n = s * math.cos(a), s * math.sin(a)
            instances.append([i % 2, c, -n, 0, move[0], n, c, 0, move[1], 0, 0, s, move[2]])
        scene = [a for m in meshes for a in ("--mesh", str(m))]
        scene += ["--instances", str(write(folder / "instances.f32", instances))]
        two = ["two/bvhlab", "two/bvhlab:batch=1", "two/bvhlab:query=stack", "flat/bvhlab:"]
        check(run(tlas_bench, [*scene, *ray_args, *(a for p in two for a in ("--peer", p))]), "tlas_bench")
    print("bench smoke: bvh_bench and tlas_bench agree")


if __name__ == "__main__":
    main()
