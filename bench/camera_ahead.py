"""The CPU tracer's wide walk with the camera rays traced ahead (a render that keeps no cost:
Renderer.start(keep_cost=False), what Renderer.render, the render CLI and the add-on's renders
ask for) against each camera ray traced alone (keep_cost=True), the same image; interleaved rounds
on one pinned core, the trace time of each render (its thread's CPU time where --cpu-time).

    python bench/camera_ahead.py [--scenes sponza,atrium] [--width 800 --height 600]
        [--samples 1] [--rounds 3] [--json camera_ahead.json]
"""

import argparse
import statistics
import time

import _common
import numpy as np


def _arguments() -> argparse.Namespace:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scenes", default="sponza,atrium")
    ap.add_argument("--width", type=int, default=800)
    ap.add_argument("--height", type=int, default=600)
    ap.add_argument("--samples", type=int, default=1, help="samples per pixel axis")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--json", default="camera_ahead.json")
    return ap.parse_args()


def _render(bvhlab, renderer, scene, bvh, args, keep_cost: bool):
    """(trace ms by the clock, thread CPU ms, the image, timings) of one whole render."""
    job = renderer.start(
        scene,
        bvh,
        args.width,
        args.height,
        samples_per_axis=args.samples,
        traversal="wide",
        threads=1,
        keep_cost=keep_cost,
    )
    cpu = time.thread_time()
    job.run()
    cpu = (time.thread_time() - cpu) * 1e3
    result = job.result(depth=False, cost=False)
    return job.timings["trace_ms"], cpu, result.color, result.timings


def main() -> None:
    args = _arguments()
    _common.pin_to_cores(1)
    import bvhlab
    from bvhlab.library import load_scene

    renderer = bvhlab.Renderer("cpu")
    out = {"machine": _common.machine(), "width": args.width, "height": args.height, "samples": args.samples}
    rows = []
    for spec in args.scenes.split(","):
        scene, name = load_scene(spec)
        bvh = bvhlab.build(scene)
        times = {True: [], False: []}
        images = {}
        ahead = 0
        for _ in range(args.rounds):
            for keep in (True, False):
                ms, cpu, image, timings = _render(bvhlab, renderer, scene, bvh, args, keep)
                times[keep].append((ms, cpu))
                images[keep] = image
                if not keep:
                    ahead = timings["camera_rays_ahead"]
        if not np.array_equal(images[True], images[False]):
            raise SystemExit(f"{name}: the images differ")
        alone = statistics.median(c for _, c in times[True])
        traced = statistics.median(c for _, c in times[False])
        rows.append(
            {
                "scene": name,
                "triangles": len(scene.triangles),
                "alone_ms": [t for t, _ in times[True]],
                "ahead_ms": [t for t, _ in times[False]],
                "alone_cpu_ms": [c for _, c in times[True]],
                "ahead_cpu_ms": [c for _, c in times[False]],
                "camera_rays_ahead": ahead,
                "ratio": traced / alone,
            }
        )
    _common.print_table(
        ["scene", "triangles", "alone ms (CPU)", "ahead ms (CPU)", "ahead ÷ alone", "camera rays ahead"],
        [
            [
                r["scene"],
                r["triangles"],
                f"{statistics.median(r['alone_cpu_ms']):.1f}",
                f"{statistics.median(r['ahead_cpu_ms']):.1f}",
                f"{r['ratio']:.3f}",
                r["camera_rays_ahead"],
            ]
            for r in rows
        ],
        title=f"CPU tracer, wide walk, {args.width}x{args.height}, {args.samples}² samples, one pinned core, "
        f"medians of {args.rounds} interleaved rounds",
    )
    out["rows"] = rows
    print(f"\nwrote {_common.write_json(args.json, out)}")


if __name__ == "__main__":
    main()
