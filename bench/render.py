"""Frame time per split method on the Vulkan renderer and the CPU reference (same tracer code).

    python bench/render.py [--scene atrium] [--width 800 --height 600] [--frames 3]

For median, mean, SAH 12 and SAH 32 (the report's Table 1 rows): average frame ms after a warm-up,
stack and stackless traversal, on Vulkan (lavapipe here) and on the CPU reference with the same
thread count, primary-ray Mrays/s, and the report's frame time beside. Writes bench/results/render.json.
"""
from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _common  # noqa: E402

METHODS = ["median", "mean", "sah12", "sah32"]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scene", default="atrium")
    ap.add_argument("--width", type=int, default=800)
    ap.add_argument("--height", type=int, default=600)
    ap.add_argument("--frames", type=int, default=3)
    args = ap.parse_args()

    import bvhlab
    from bvhlab.compare import REPORT_TABLE1, measure_methods
    from bvhlab.library import load_scene

    scene, name = load_scene(args.scene)
    threads = os.cpu_count()
    results = {"machine": _common.machine(), "scene": name, "triangles": len(scene.triangles),
               "width": args.width, "height": args.height, "threads": threads, "rows": []}
    renderers = {"vulkan": bvhlab.Renderer("vulkan"), "cpu": bvhlab.Renderer("cpu")}
    for backend, renderer in renderers.items():
        for traversal in ("stack", "stackless"):
            rows = measure_methods(scene, METHODS, frames=args.frames, builds=1, width=args.width,
                                   height=args.height, renderer=renderer,
                                   progress=lambda s: print(f"  [{backend} {traversal}] {s}", file=sys.stderr),
                                   render_options={"traversal": traversal})
            for r in rows:
                results["rows"].append({**r, "backend": backend, "traversal": traversal})
    table = []
    for m in METHODS:
        cell = {(r["backend"], r["traversal"]): r for r in results["rows"] if r["method"] == m}
        vk, cpu = cell[("vulkan", "stack")], cell[("cpu", "stack")]
        table.append([m, vk["frame_ms"], cell[("vulkan", "stackless")]["frame_ms"], cpu["frame_ms"],
                      cell[("cpu", "stackless")]["frame_ms"], vk["frame_ms"] / cpu["frame_ms"],
                      vk["primary_mrays_s"], cpu["primary_mrays_s"], REPORT_TABLE1[m][0]])
    _common.print_table(["method", "vulkan stack", "vulkan stackless", "cpu stack", "cpu stackless",
                         "vulkan/cpu", "vk prim Mrays/s", "cpu prim Mrays/s", "report ms"], table,
                        title=f"\n{name}: frame ms at {args.width}x{args.height}; Vulkan on "
                              f"{renderers['vulkan'].device}, CPU reference on {threads} threads")
    print(f"\nwrote {_common.write_json('render.json', results)}")


if __name__ == "__main__":
    main()
