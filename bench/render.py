"""Frame time per split method on the Vulkan renderer and the CPU reference (same tracer code).

    python bench/render.py [--scene atrium] [--width 800 --height 600] [--frames 3] [--json NAME]

For median, mean, SAH 12 and SAH 32 (the report's Table 1 rows): median frame ms after a warm-up,
stack and stackless traversal, on Vulkan (lavapipe here) and on the CPU reference with the same
thread count (and its wide traversal, the same image), primary-ray Mrays/s, and the report's frame
time beside.

Then the cost of bounded dispatches (issue 8): the SAH 12 tree rendered with the steps one pixel
may run per dispatch fixed at 60000 (most frames: one round per tile), 4096, 512 and 64, and left to
the renderer (adaptive), interleaved and repeated; frame ms, trace dispatches, and the ratio to
the 60000 budget. On the CPU reference the budget only decides how often a trace is saved and
loaded. Writes bench/results/render.json.
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _common  # noqa: E402

METHODS = ["median", "mean", "sah12", "sah32"]


def _arguments() -> argparse.Namespace:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scene", default="atrium")
    ap.add_argument("--width", type=int, default=800)
    ap.add_argument("--height", type=int, default=600)
    ap.add_argument("--frames", type=int, default=3)
    ap.add_argument("--samples-per-axis", type=int, default=1, help="for the bounded-dispatch table")
    ap.add_argument("--skip-table1", action="store_true", help="only the bounded-dispatch table")
    ap.add_argument(
        "--json", help="results file name in bench/results (or a path); default render.json (render_budgets.json)"
    )
    return ap.parse_args()


def main() -> None:
    args = _arguments()
    import bvhlab
    from bvhlab.library import load_scene

    scene, name = load_scene(args.scene)
    threads = os.cpu_count()
    results = {
        "machine": _common.machine(),
        "scene": name,
        "triangles": len(scene.triangles),
        "width": args.width,
        "height": args.height,
        "threads": threads,
        "rows": [],
    }
    renderers = {"vulkan": bvhlab.Renderer("vulkan"), "cpu": bvhlab.Renderer("cpu")}
    results["budgets"] = budget_rows(bvhlab, scene, name, renderers, args)
    if args.skip_table1:
        print(f"\nwrote {_common.write_json(args.json or 'render_budgets.json', results)}")
        return
    results["rows"] = _measure_table1(scene, renderers, args)
    _print_table1(
        results["rows"],
        title=f"\n{name}: frame ms at {args.width}x{args.height}; Vulkan on "
        f"{renderers['vulkan'].device}, CPU reference on {threads} threads",
    )
    print(f"\nwrote {_common.write_json(args.json or 'render.json', results)}")


def _measure_table1(scene, renderers: dict, args) -> list[dict]:
    """The report's methods on each backend and traversal (bvhlab compare's protocol)."""
    import bvhlab
    from bvhlab.compare import measure_methods

    rows = []
    for backend, renderer in renderers.items():
        for traversal in ("stack", "stackless", "wide") if backend == "cpu" else ("stack", "stackless"):
            measured = measure_methods(
                scene,
                METHODS,
                frames=args.frames,
                builds=1,
                width=args.width,
                height=args.height,
                renderer=renderer,
                progress=lambda s, backend=backend, traversal=traversal: print(
                    f"  [{backend} {traversal}] {s}", file=sys.stderr
                ),
                options=bvhlab.RenderOptions(traversal=traversal),
            )
            rows += [{**r, "backend": backend, "traversal": traversal} for r in measured]
    return rows


def _print_table1(rows: list[dict], title: str) -> None:
    from bvhlab.compare import REPORT_TABLE1

    table = []
    for m in METHODS:
        cell = {(r["backend"], r["traversal"]): r for r in rows if r["method"] == m}
        vk, cpu = cell[("vulkan", "stack")], cell[("cpu", "stack")]
        table.append(
            [
                m,
                vk["frame_ms"],
                cell[("vulkan", "stackless")]["frame_ms"],
                cpu["frame_ms"],
                cell[("cpu", "stackless")]["frame_ms"],
                cell[("cpu", "wide")]["frame_ms"],
                cpu["frame_ms"] / cell[("cpu", "wide")]["frame_ms"],
                vk["frame_ms"] / cpu["frame_ms"],
                "{trace_ms:.1f} / {readback_ms:.1f}".format(**vk["last_frame"]),
                vk["primary_mrays_s"],
                cpu["primary_mrays_s"],
                REPORT_TABLE1[m][0],
            ]
        )
    header = ["method", "vulkan stack", "vulkan stackless", "cpu stack", "cpu stackless", "cpu wide"]
    header += ["cpu stack/wide", "vulkan/cpu"]
    header += ["vk stack trace / readback ms (last frame)"]
    header += ["vk prim Mrays/s", "cpu prim Mrays/s", "report ms"]
    _common.print_table(header, table, title=title)


BUDGETS = [60000, 4096, 512, 64, None]


def budget_rows(bvhlab, scene, name, renderers, args) -> list[dict]:
    """Frame ms per steps-per-dispatch budget, interleaved over `frames` rounds (min of each)."""
    bvh = bvhlab.build(scene, method="sah", bins=12)
    options = {"samples_per_axis": args.samples_per_axis}
    times = {(b, k): [] for b in renderers for k in range(len(BUDGETS))}
    dispatches = {}
    for renderer in renderers.values():  # warm-up: shaders compiled, scene uploaded
        renderer.render(scene, bvh, args.width, args.height, **options)
    for _ in range(max(1, args.frames)):
        for k, budget in enumerate(BUDGETS):
            for backend, renderer in renderers.items():
                extra = {} if budget is None else {"steps_per_dispatch": budget}
                _, t = renderer.render(scene, bvh, args.width, args.height, **options, **extra)
                times[(backend, k)].append(t["overlay_ms"] + t["trace_ms"] + t["readback_ms"])
                dispatches[(backend, k)] = t["dispatches"]
    rows, table = [], []
    for k, budget in enumerate(BUDGETS):
        row = {"steps_per_dispatch": budget or "adaptive"}
        for backend in renderers:
            row[f"{backend}_ms"] = min(times[(backend, k)])
            row[f"{backend}_ratio"] = row[f"{backend}_ms"] / min(times[(backend, 0)])
            row[f"{backend}_dispatches"] = dispatches[(backend, k)]
        rows.append(row)
        table.append(
            [
                row["steps_per_dispatch"],
                row["vulkan_ms"],
                row["vulkan_dispatches"],
                row["vulkan_ratio"],
                row["cpu_ms"],
                row["cpu_ratio"],
            ]
        )
    _common.print_table(
        ["steps/dispatch", "vulkan ms", "dispatches", "vs 60000", "cpu ms", "vs 60000"],
        table,
        title=f"\n{name}, SAH 12, {args.width}x{args.height}, {args.samples_per_axis}x"
        f"{args.samples_per_axis} samples: frame ms by steps per dispatch "
        f"(min of {max(1, args.frames)}, interleaved)",
    )
    return rows


if __name__ == "__main__":
    main()
