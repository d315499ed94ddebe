"""Objects used once that move (issue 34), bpy as a module: a static Suzanne of 251,904 triangles
(four subdivisions), a floor, and a keyframed Suzanne (968 triangles) moving over frames 1-24.
With movers (the animated object a mesh and an instance of its own) each frame change makes a new
TLAS only; without them (the layout before: every object used once in mesh 0) mesh 0's tree is
updated with the scene's policy (adaptive) every frame. Per frame: the sync (LiveScene, inside
Blender's frame_change_post handler, as the add-on's follow and the engine do) and the tree
update (trees.SceneTree.update); then the trace cost of the two layouts (closest hits of random
rays, and the camera's image on the CPU reference, one thread: the two-level walk over the
promoted object against one flat tree), and the
export of 10,000 collection instances (what asking every item whether it is animated costs).

    .venv/bin/python bench/moving_objects.py [--frames 24] [--repeat 3]
        [--json bench/results/moving_objects.json]

Medians over the frames, best of --repeat for the rest (the machine is shared: timings vary
1.5-2x by the hour)."""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import time
from importlib import import_module
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests" / "blender"))
sys.path.insert(0, str(ROOT / "tests" / "python"))

import bpy  # noqa: E402
import numpy as np  # noqa: E402
from export_instances import best, scene_of  # noqa: E402

import bvhlab.blender.live as live_module  # noqa: E402

_PLAN = live_module.plan


def movers(on: bool) -> None:
    """Movers on (the exporter as it is) or off (every object used once in mesh 0, as before)."""

    def plan_without_movers(items, matrices, share, is_mover=None):
        return _PLAN(items, matrices, share)

    live_module.plan = _PLAN if on else plan_without_movers


def moving_scene(frames: int):
    from blender_instance_scenes import base_scene, suzanne

    scene = base_scene()
    big = suzanne("Big", subdivisions=4)
    scene.collection.objects.link(big)
    big.location = (-1.5, 2.0, 0.0)
    floor = bpy.data.objects.new("Floor", bpy.data.meshes.new("Floor"))
    floor.data.from_pydata([(-8, -8, -1.5), (8, -8, -1.5), (8, 8, -1.5), (-8, 8, -1.5)], [], [(0, 1, 2, 3)])
    scene.collection.objects.link(floor)
    small = suzanne("Mover")
    scene.collection.objects.link(small)
    small.location = (2.0, -2.0, 0.0)
    small.keyframe_insert("location", frame=1)
    small.location = (3.0, 2.0, 1.0)
    small.keyframe_insert("location", frame=frames)
    scene.frame_start, scene.frame_end = 1, frames
    scene.frame_set(1)
    return scene


def play(scene, frames: int, tree_class) -> dict:
    """Sync and update over frames 2..frames; returns per-frame medians and the tree at the end."""
    from bvhlab.blender import LiveScene

    live = LiveScene("visible", require_camera=False)
    tree = tree_class(scene.bvhlab.build_config())
    scene.frame_set(1)
    live.sync(bpy.context.evaluated_depsgraph_get(), scene)
    tree.update(live.scene)
    syncs, updates, actions = [], [], []

    def on_frame(scene, depsgraph):
        start = time.perf_counter()
        report = live.sync(depsgraph, scene)
        middle = time.perf_counter()
        update = tree.update(live.scene, report.refittable)
        syncs.append((middle - start) * 1e3)
        updates.append((time.perf_counter() - middle) * 1e3)
        actions.append(update.action)

    bpy.app.handlers.frame_change_post.append(on_frame)
    try:
        for frame in range(2, frames + 1):
            scene.frame_set(frame)
    finally:
        bpy.app.handlers.frame_change_post.remove(on_frame)
    return (
        {
            "sync_ms": statistics.median(syncs),
            "update_ms": statistics.median(updates),
            "actions": sorted(set(actions)),
            "meshes": live.scene.mesh_count,
            "triangles_in_mesh_0": len(live.scene.triangles),
        },
        tree,
        live.scene,
    )


def trace_ms(layouts: dict, repeat: int, count: int = 200_000) -> dict:
    """Best of `repeat` interleaved rounds: closest hits of the same random rays (origins in the
    scene's box, directions uniform) through each layout's tree, on one thread."""
    lo, hi = next(iter(layouts.values()))[1].bounds()
    rng = np.random.default_rng(7)
    origins = rng.uniform(lo, hi, (count, 3)).astype(np.float32)
    directions = rng.normal(size=(count, 3)).astype(np.float32)
    times: dict = {label: [] for label in layouts}
    hits = {}
    for _ in range(repeat):
        for label, (tree, _) in layouts.items():
            start = time.perf_counter()
            hits[label] = tree.bvh.intersect(origins, directions, threads=1)["t"]
            times[label].append((time.perf_counter() - start) * 1e3)
    first, *others = hits.values()
    assert all(np.allclose(first, h, rtol=1e-5) for h in others), "the layouts hit differently"
    return {label: min(t) for label, t in times.items()}


def render_ms(layouts: dict, repeat: int, width: int = 320, height: int = 240) -> dict:
    """Best of `repeat` interleaved rounds: the CPU reference's trace time of the camera's image
    (1 sample per pixel, shadows and bounces), on one thread."""
    import bvhlab

    renderer = bvhlab.Renderer("cpu", threads=1)
    times: dict = {label: [] for label in layouts}
    for _ in range(repeat):
        for label, (tree, exported) in layouts.items():
            _, timings = renderer.render(exported, tree.bvh, width, height, samples_per_axis=1)
            times[label].append(timings["trace_ms"])
    return {label: min(t) for label, t in times.items()}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=24)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--json", type=Path, default=ROOT / "bench" / "results" / "moving_objects.json")
    args = parser.parse_args()
    import harness

    from bvhlab.blender import export_scene

    harness.enable_addon_from_source()
    trees = import_module(harness.addon().__name__ + ".trees")
    rows, layouts = {}, {}
    for label, on in (("movers", True), ("mesh 0", False)):  # the same scene each
        movers(on)
        scene = moving_scene(args.frames)
        rows[label], *layouts[label] = play(scene, args.frames, trees.SceneTree)
    for label, ms in trace_ms(layouts, args.repeat).items():
        rows[label]["trace_200k_rays_ms"] = ms
    for label, ms in render_ms(layouts, args.repeat).items():
        rows[label]["render_320x240_trace_ms"] = ms
    for label, on in (("movers", True), ("mesh 0", False)):
        movers(on)
        scene_of(10_000)
        rows[label]["export_10000_instances_ms"], _ = best(lambda: export_scene(bpy.context), args.repeat)
    movers(True)
    for label, row in rows.items():
        print(label, json.dumps(row))
    args.json.parent.mkdir(parents=True, exist_ok=True)
    note = (
        f"per-frame medians over frames 2-{args.frames}; best of {args.repeat} interleaved rounds for trace and "
        "render, best of them for export; one run on the shared 2-core machine, other helpers loading it"
    )
    args.json.write_text(json.dumps({"note": note, "rows": rows}, indent=1) + "\n")


if __name__ == "__main__":
    main()
