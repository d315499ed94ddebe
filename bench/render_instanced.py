"""The two-level tracer (issue 34) on the CPU reference, one thread: frame ms of a flat scene (the
flat path must not get slower), of the same mesh as one identity instance of an InstancedBvh (the
flat render scene), and of many instances of one mesh against the flattened scene's tree (frame ms,
primary Mrays/s, the trees' bytes), each by the stack, stackless and wide traversals. The least of
`--repeat` frames (the machine is shared).

    .venv/bin/python bench/render_instanced.py [--flat-only] [--json]

`--flat-only` times the flat scene alone, with whatever bvhlab is on the path: run it with an older
build's package on PYTHONPATH for a before/after figure.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

import bvhlab  # noqa: E402
from bvhlab.library import procedural  # noqa: E402

WIDTH, HEIGHT = 320, 240
TRAVERSALS = bvhlab.TRAVERSALS  # wide: the CPU tracer's (the 8-wide copies, the same image)


def frame_ms(scene, tree, repeat: int, traversal: str) -> float:
    renderer = bvhlab.Renderer("cpu", threads=1)
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        renderer.render(scene, tree, WIDTH, HEIGHT, traversal=traversal, max_depth=2)
        times.append(time.perf_counter() - t)
    return min(times) * 1e3


def grid(n_side: int, seed: int) -> np.ndarray:
    """n_side² instances on a grid: random rotations about z, scales 0.6-1.2 (some mirrored)."""
    rng = np.random.default_rng(seed)
    n = n_side * n_side
    t = np.zeros((n, 3, 4), np.float32)
    a = rng.uniform(0, 2 * np.pi, n)
    s = rng.uniform(0.6, 1.2, (n, 3)) * rng.choice([-1, 1], (n, 1), p=[0.25, 0.75])
    t[:, 0, 0], t[:, 0, 1], t[:, 1, 0], t[:, 1, 1] = (
        np.cos(a) * s[:, 0],
        -np.sin(a) * s[:, 1],
        np.sin(a) * s[:, 0],
        np.cos(a) * s[:, 1],
    )
    t[:, 2, 2] = s[:, 2]
    xy = np.stack(np.meshgrid(np.arange(n_side), np.arange(n_side)), -1).reshape(-1, 2) * 3.0
    t[:, 0, 3], t[:, 1, 3] = xy[:, 0], xy[:, 1]
    return t


def camera_for(scene) -> bvhlab.Camera:
    lo, hi = scene.bounds()
    c = (lo + hi) / 2
    d = float(np.linalg.norm(hi - lo))
    return bvhlab.Camera(tuple(c + np.array([0.3, -0.8, 0.6]) * d), tuple(c), (0.0, 0.0, 1.0), 45.0)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--flat-only", action="store_true")
    ap.add_argument("--json", action="store_true")
    ap.add_argument("--scene", help="the flat scene (a library name, e.g. atrium); default: a 100K torus knot")
    args = ap.parse_args()
    knot = procedural.torus_knot(100_000)
    flat = bvhlab.Scene(triangles=knot)
    flat.camera = camera_for(flat)
    if args.scene:
        from bvhlab.library import load_scene

        flat, _ = load_scene(args.scene)
    flat_tree = bvhlab.build(flat)
    rows: dict = {}
    for traversal in TRAVERSALS:
        rows[f"flat_{traversal}_ms"] = frame_ms(flat, flat_tree, args.repeat, traversal)
    if not args.flat_only:
        mesh_of, transforms = flat.instances()
        one = bvhlab.Scene(
            triangles=flat.triangles,
            spheres=flat.spheres,
            materials=list(flat.materials),
            tri_material=flat.tri_material,
            sphere_material=flat.sphere_material,
            instance_mesh=mesh_of,
            instance_transforms=transforms,
            camera=flat.camera,
            light=flat.light,
        )
        one_tree = bvhlab.build(one)
        rows["one_instance_stack_ms"] = frame_ms(one, one_tree, args.repeat, "stack")
        mesh = procedural.torus_knot(20_000)
        many = bvhlab.Scene(triangles=mesh, instance_mesh=np.zeros(100, int), instance_transforms=grid(10, 1))
        many.camera = camera_for(many)
        many_tree = bvhlab.build(many)
        flattened = many.flattened()
        flat_many_tree = bvhlab.build(flattened)
        for traversal in TRAVERSALS:
            rows[f"instanced_100x20k_{traversal}_ms"] = frame_ms(many, many_tree, args.repeat, traversal)
            rows[f"flattened_2M_{traversal}_ms"] = frame_ms(flattened, flat_many_tree, args.repeat, traversal)
        s = many_tree.stats
        rows["instanced_tree_bytes"] = s["tlas_memory_bytes"] + s["meshes_memory_bytes"]
        rows["flattened_tree_bytes"] = flat_many_tree.stats["memory_bytes"]
    rays = WIDTH * HEIGHT
    for k, v in list(rows.items()):
        if k.endswith("_ms"):
            rows[k.replace("_ms", "_primary_mrays_s")] = rays / (v * 1e3)
    print(json.dumps(rows, indent=1) if args.json else "\n".join(f"{k:40} {v:12.2f}" for k, v in rows.items()))


if __name__ == "__main__":
    main()
