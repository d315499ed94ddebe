"""The render engine's Rendered viewport on the bundled atrium, measured through the viewport's own
worker (addon/engine/viewport.py: the code view_draw drives), without a window:

- frame times of each level for a view seen for the first time: preview (the resolution that
  fits the preview budget), full (the region's resolution, 1 sample), refined (2×2 samples);
- the report's §4.1 claim: a frame with the BVH boxes of depths 8-9 traced in against one without
  (full level, same view), the two interleaved, --rounds times each.

    .venv/bin/python bench/viewport.py [--size 1322x784] [--views 5] [--rounds 7] [--traversal stackless]
        [--json bench/results/viewport.json]

The region size default is the 3D viewport of `make blender-ui-test` (1600 × 900 window). The
viewport traces on all cores but one (VIEWPORT_THREADS); times are the tracer's own (overlay pass +
trace pass: `total_ms`), medians with the spread printed. The machine is shared: run it pinned
(`taskset -c 1`) and more than once."""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests" / "blender"))
import bpy  # noqa: E402
import harness  # noqa: E402  (before bpy: a private user folder)


def _modules():
    from importlib import import_module

    harness.enable_addon_from_source()
    package = harness.addon().__name__ + ".engine."
    modules = {name: import_module(package + name) for name in ("viewport", "view_camera", "settings")}
    modules["trees"] = import_module(harness.addon().__name__ + ".trees")  # the add-on's one tree cache
    return modules


TRAVERSAL = "stackless"  # --traversal


def _request(m, scene, width, height, turn: float, samples_per_axis: int, overlay):
    """A ViewRequest for the scene camera's view turned by `turn` radians about the vertical."""
    from mathutils import Matrix

    depsgraph = bpy.context.evaluated_depsgraph_get()
    camera = scene.camera.evaluated_get(depsgraph)
    world = Matrix.Rotation(turn, 4, "Z") @ camera.matrix_world
    view_matrix = world.inverted()
    window = camera.calc_matrix_camera(depsgraph, x=width, y=height)
    frustum = m["view_camera"].view_frustum(view_matrix, window, width, height)
    scene.bvhlab.traversal = TRAVERSAL
    settings = scene.bvhlab.render_options(viewport=True).replace(
        samples_per_axis=samples_per_axis, max_depth=5, overlay_depth=overlay
    )
    tree = m["trees"].key_of(scene, scope="visible")
    return m["viewport"].ViewRequest(frustum, settings, "auto", tree, budget_ms=40.0)


def _wait_for(session, request, level: str, timeout: float = 600.0):
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        frame = session.latest_frame()
        if frame is not None and frame.request == request and frame.level == level:
            return frame
        time.sleep(0.005)
    raise TimeoutError(f"no {level} frame within {timeout} s")


def _levels(m, session, scene, width, height, views: int) -> dict:
    """Per level: tracer time and latency (view handed over → frame ready) of `views` new views."""
    out: dict = {"preview": [], "full": [], "refined": []}
    for k in range(views):
        request = _request(m, scene, width, height, 0.02 * (k + 1), samples_per_axis=2, overlay=None)
        session.request(request)
        seen = set()
        while len(seen) < 3:
            frame = session.latest_frame()
            if frame is not None and frame.request == request and frame.level not in seen:
                seen.add(frame.level)
                t = frame.timings
                out[frame.level].append(
                    {"width": t["width"], "height": t["height"], "ms": t["frame_ms"], "latency_ms": t["latency_ms"]}
                )
            time.sleep(0.002)
    return out


def _section_41(m, session, scene, width, height, rounds: int) -> dict:
    times: dict = {"no boxes": [], "boxes 8-9": []}
    for k in range(rounds):
        for name, overlay in (("no boxes", None), ("boxes 8-9", (8, 9))):
            request = _request(m, scene, width, height, 0.0, samples_per_axis=1, overlay=overlay)
            session.request(request)
            frame = _wait_for(session, request, "full")
            times[name].append(frame.timings["total_ms"])
            session.request(
                _request(m, scene, width, height, 0.5 + 0.01 * k, samples_per_axis=1, overlay=None)
            )  # move away
            time.sleep(0.3)
    return times


def _spread(values) -> str:
    return f"median {statistics.median(values):7.1f} ms (min {min(values):.1f}, max {max(values):.1f}, n={len(values)})"


def _report(header: str, levels: dict, section: dict) -> list[float]:
    """Prints the frame times per level and the §4.1 comparison; returns the per-round ratios
    of the frame with boxes to the frame without."""
    print(header)
    for level, runs in levels.items():
        sizes = {(r["width"], r["height"]) for r in runs}
        print(
            f"  {level:8s} {sorted(sizes)}: frame {_spread([r['ms'] for r in runs])}; "
            f"latency {_spread([r['latency_ms'] for r in runs])}"
        )
    print("  report §4.1, full level, 1 sample, same view:")
    for name, values in section.items():
        print(f"    {name:10s} {_spread(values)}")
    ratios = [b / n for b, n in zip(section["boxes 8-9"], section["no boxes"])]
    print(
        f"    boxes / none per round: median {statistics.median(ratios):.3f} "
        f"(min {min(ratios):.3f}, max {max(ratios):.3f})"
    )
    return ratios


def main() -> None:
    global TRAVERSAL
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--size", default="1322x784")
    ap.add_argument("--views", type=int, default=5)
    ap.add_argument("--rounds", type=int, default=7)
    ap.add_argument("--json", type=Path, default=ROOT / "bench" / "results" / "viewport.json")
    ap.add_argument("--traversal", default=TRAVERSAL, help="the tracer's: stack, stackless, wide (CPU) or auto")
    args = ap.parse_args()
    TRAVERSAL = args.traversal
    width, height = (int(v) for v in args.size.split("x"))
    m = _modules()
    scene = harness.open_scene("atrium")
    from bvhlab.blender import LiveScene

    live = LiveScene("visible", require_camera=False)
    live.sync(bpy.context.evaluated_depsgraph_get(), scene, bpy.context.view_layer)
    session = m["viewport"].ViewportSession()
    session.set_scene(live.scene, None)
    first = _request(m, scene, width, height, 0.0, samples_per_axis=1, overlay=None)
    session.request(first)
    build_frame = _wait_for(session, first, "full")
    levels = _levels(m, session, scene, width, height, args.views)
    section = _section_41(m, session, scene, width, height, args.rounds)
    session.close()
    device = build_frame.timings["device"]
    header = (
        f"atrium {len(live.scene.triangles):,} triangles, viewport {width} × {height}, {device}, {TRAVERSAL}, "
        f"{m['settings'].VIEWPORT_THREADS} thread(s); tree built in {build_frame.timings['build_ms']:.0f} ms"
    )
    ratios = _report(header, levels, section)
    result = {
        "size": [width, height],
        "device": device,
        "traversal": TRAVERSAL,
        "threads": m["settings"].VIEWPORT_THREADS,
        "build_ms": build_frame.timings["build_ms"],
        "levels": levels,
        "section_4_1_ms": section,
        "section_4_1_ratio_median": statistics.median(ratios),
    }
    args.json.parent.mkdir(parents=True, exist_ok=True)
    args.json.write_text(json.dumps(result, indent=1) + "\n")
    print(f"wrote {args.json}")


if __name__ == "__main__":
    # report the outcome and skip bpy's teardown (harness.exit_without_teardown), on success and on failure
    import traceback

    exit_code = 0
    try:
        main()
    except Exception:
        traceback.print_exc()
        exit_code = 1
    harness.exit_without_teardown(exit_code)
