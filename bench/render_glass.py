"""The CPU tracer's walks in scenes with glass: frame ms of the stack and the wide walk (the same
image), stack and wide interleaved in each round, and the shadow rays the wide walk answered by
their nearest crossing (opaque: transmission 0 from the wide walk; glass: left to the stack walk,
which multiplies the crossings in its own order). A bundled scene is rendered as it is and with
one of its materials made glass (transparent 0.7, ior 1.5): the one of fewest triangles, as a
window in a room, unless --glass names it.

    .venv/bin/python bench/render_glass.py [--scenes atrium,gen:whitted] [--size 640x360]
        [--rounds 3] [--threads 1] [--glass K] [--json render_glass.json]

Pinned to as many cores as threads; medians of the rounds; wide ÷ stack is the median of the
rounds' ratios (the machine's speed moves between rounds, not within one).
"""

from __future__ import annotations

import argparse
import dataclasses
import statistics
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _common import json_path, machine, machine_line, pin_to_cores, print_table, write_json  # noqa: E402

import bvhlab  # noqa: E402
from bvhlab.library import load_scene  # noqa: E402

TRAVERSALS = ("stack", "wide")


def with_glass(scene: bvhlab.Scene, glass: int | None) -> tuple[bvhlab.Scene, int] | None:
    """The scene with material `glass` (default: the one of fewest triangles) made transparent;
    None where the scene has glass already or has no triangles' materials to change."""
    if any(m.transparent > 0 for m in scene.materials) or scene.tri_material is None or not len(scene.materials):
        return None
    if glass is None:
        counts = np.bincount(scene.tri_material, minlength=len(scene.materials))
        glass = int(np.argmin(np.where(counts > 0, counts, counts.max() + 1)))
    materials = list(scene.materials)
    materials[glass] = dataclasses.replace(materials[glass], transparent=0.7, ior=1.5)
    return dataclasses.replace(scene, materials=materials), glass


def frame(renderer, scene, bvh, size, traversal) -> dict:
    start = time.perf_counter()
    _, timings = renderer.render(scene, bvh, *size, traversal=traversal)
    return {
        "wall_ms": (time.perf_counter() - start) * 1e3,
        "trace_ms": timings["trace_ms"],
        "shadow_rays_opaque": timings["shadow_rays_opaque"],
        "shadow_rays_glass": timings["shadow_rays_glass"],
        "device": timings["device"],
    }


def measure(label, scene, bvh, size, rounds, threads) -> dict:
    renderer = bvhlab.Renderer("cpu", threads=threads)
    runs = {t: [] for t in TRAVERSALS}
    frame(renderer, scene, bvh, size, "wide")  # makes the wide copy (kept with the tree)
    for _ in range(rounds):
        for t in TRAVERSALS:
            runs[t].append(frame(renderer, scene, bvh, size, t))
    return {"scene": label, "runs": runs}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scenes", default="atrium,gen:whitted")
    ap.add_argument("--size", default="640x360")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--glass", type=int, default=None, help="the material made glass (default: fewest triangles)")
    ap.add_argument("--json", default="render_glass.json")
    args = ap.parse_args()
    json_path(args.json)  # a folder that does not exist fails now, not after the renders
    size = tuple(int(v) for v in args.size.split("x"))
    pin_to_cores(args.threads)  # as many cores as threads: the other's load moves the figures less
    m = machine()
    print(machine_line(m))
    results, rows = [], []
    for spec in args.scenes.split(","):
        scene, name = load_scene(spec)
        bvh = bvhlab.build(scene)
        variants = [(name, scene)]
        glassy = with_glass(scene, args.glass)
        if glassy is not None:
            variants.append((f"{name}, material {glassy[1]} glass", glassy[0]))
        for label, variant in variants:
            r = measure(label, variant, bvh, size, args.rounds, args.threads)
            results.append(r)
            stack, wide = r["runs"]["stack"], r["runs"]["wide"]
            last = wide[-1]
            rows.append(
                [
                    label,
                    statistics.median(x["trace_ms"] for x in stack),
                    statistics.median(x["trace_ms"] for x in wide),
                    statistics.median(w["trace_ms"] / s["trace_ms"] for w, s in zip(wide, stack)),
                    last["shadow_rays_opaque"],
                    last["shadow_rays_glass"],
                ]
            )
    print_table(
        ["scene", "stack ms", "wide ms", "wide ÷ stack", "shadow rays: opaque first (wide)", "glass first (stack)"],
        rows,
        f"CPU tracer at {size[0]}×{size[1]}, {args.threads} thread(s), medians of {args.rounds} interleaved rounds",
    )
    print(
        f"wrote {write_json(args.json, {'machine': m, 'rounds': args.rounds, 'size': list(size), 'scenes': results})}"
    )


if __name__ == "__main__":
    main()
