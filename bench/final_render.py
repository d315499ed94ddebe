"""F12 through the render engine (`bpy.ops.render.render`, bpy as a module) on bundled scenes, with
each Traversal in turn, interleaved: the engine's own trace time (its Last Render record) and the
operator's wall time. With Traversal Auto (the add-on's default) the CPU tracer walks the trees'
8-wide copies; Stack is the report's walk (and Auto's where a count is shown): the same image.

    .venv/bin/python bench/final_render.py [--scenes atrium,whitted] [--size 1280x720]
        [--traversals stack,auto] [--rounds 3] [--threads 0] [--json final_render.json]

The tree is built by the first F12 of a scene and kept (the add-on's tree cache): the figures
are of the renders after it. Medians of the rounds, each traversal's ratio to the first's per
round (the machine's speed moves between rounds, not within one)."""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests" / "blender"))
sys.path.insert(0, str(ROOT / "bench"))
import bpy  # noqa: E402
import harness  # noqa: E402  (before bpy: a private user folder)
from _common import json_path, machine, machine_line, print_table, write_json  # noqa: E402


def _f12(scene) -> dict:
    start = time.perf_counter()
    assert bpy.ops.render.render() == {"FINISHED"}
    wall_ms = (time.perf_counter() - start) * 1e3
    record = harness.addon().state.last_final[scene.session_uid]
    return {"wall_ms": wall_ms, "trace_ms": record["trace_ms"], "device": record["device"]}


def measure(name: str, size: tuple[int, int], traversals: list[str], rounds: int, threads: int) -> dict:
    scene = harness.open_scene(name)
    scene.render.engine = "BVHLAB_WHITTED"
    scene.render.resolution_x, scene.render.resolution_y = size
    scene.render.resolution_percentage = 100
    scene.render.threads_mode, scene.render.threads = ("FIXED", threads) if threads else ("AUTO", 1)
    scene.bvhlab.backend = "cpu"
    _f12(scene)  # builds and keeps the tree
    runs: dict[str, list[dict]] = {t: [] for t in traversals}
    for _ in range(rounds):
        for traversal in traversals:
            scene.bvhlab.traversal = traversal
            runs[traversal].append(_f12(scene))
    return {"scene": name, "size": list(size), "runs": runs}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scenes", default="atrium,whitted")
    ap.add_argument("--size", default="1280x720")
    ap.add_argument("--traversals", default="stack,auto")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--threads", type=int, default=0, help="Blender's render threads (0: as Blender picks)")
    ap.add_argument("--json", default="final_render.json")
    args = ap.parse_args()
    json_path(args.json)  # a folder that does not exist fails now, not after the renders
    size = tuple(int(v) for v in args.size.split("x"))
    traversals = args.traversals.split(",")
    harness.enable_addon_from_source()
    m = machine()
    print(machine_line(m))
    results, rows = [], []
    for name in args.scenes.split(","):
        r = measure(name, size, traversals, args.rounds, args.threads)
        results.append(r)
        first = r["runs"][traversals[0]]
        for t in traversals:
            runs = r["runs"][t]
            ratios = [a["trace_ms"] / b["trace_ms"] for a, b in zip(runs, first)]
            rows.append(
                [
                    name,
                    t,
                    statistics.median(x["trace_ms"] for x in runs),
                    statistics.median(x["wall_ms"] for x in runs),
                    statistics.median(ratios),
                    runs[-1]["device"],
                ]
            )
    print_table(
        ["scene", "traversal", "trace ms", "F12 wall ms", f"trace ÷ {traversals[0]}", "device"],
        rows,
        f"F12 at {size[0]}×{size[1]}, medians of {args.rounds} interleaved rounds",
    )
    print(f"wrote {write_json(args.json, {'machine': m, 'rounds': args.rounds, 'scenes': results})}")


if __name__ == "__main__":
    main()
