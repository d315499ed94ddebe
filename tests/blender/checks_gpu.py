"""Checks that draw with Blender's `gpu` module. Run them in their own process (Blender aborts the
process when GPU start-up fails): tests/blender/run.py --only gpu."""
from __future__ import annotations

import math
import time
from importlib import import_module

import numpy as np

import harness
import bpy
import bvhlab
from bvhlab.library import procedural
from bvhlab.blender import export_scene

#: The 12 edges of a box as pairs of corner selectors (0 = min, 1 = max per axis).
EDGES = [((a, b, 0), (a, b, 1)) for a in (0, 1) for b in (0, 1)] + \
        [((a, 0, b), (a, 1, b)) for a in (0, 1) for b in (0, 1)] + \
        [((0, a, b), (1, a, b)) for a in (0, 1) for b in (0, 1)]


def ensure_gpu_context() -> None:
    """Background Blender has no GPU context until it renders something: a 4×4 Workbench frame."""
    scene = bpy.context.scene
    engine, size = scene.render.engine, (scene.render.resolution_x, scene.render.resolution_y)
    scene.render.engine = "BLENDER_WORKBENCH"
    scene.render.resolution_x = scene.render.resolution_y = 4
    bpy.ops.render.render()
    scene.render.engine = engine
    scene.render.resolution_x, scene.render.resolution_y = size


def _overlay_package():
    return import_module(harness.addon().__name__ + ".overlay")


def _project(points: np.ndarray, camera, width: int, height: int) -> np.ndarray:
    """Pixel coordinates (x right, y up from the bottom row) of world points through the exported
    pinhole camera: numpy only, no Blender matrices."""
    position, look_at, up = (np.array(v, np.float64) for v in (camera.position, camera.look_at, camera.up))
    forward = (look_at - position) / np.linalg.norm(look_at - position)
    right = np.cross(forward, up)
    right /= np.linalg.norm(right)
    true_up = np.cross(right, forward)
    d = points - position
    depth = d @ forward
    tan = math.tan(math.radians(camera.fov_y) / 2)
    ndc_x = (d @ right) / (depth * tan * width / height)
    ndc_y = (d @ true_up) / (depth * tan)
    return np.stack([(ndc_x + 1) / 2 * width, (ndc_y + 1) / 2 * height], -1)


def _segment_distance(pixels: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Distance from each pixel centre (P,2) to the nearest of the segments a→b (S,2)."""
    ab = b - a
    t = np.clip(((pixels[:, None] - a) * ab).sum(-1) / np.maximum((ab * ab).sum(-1), 1e-12), 0, 1)
    closest = a + t[..., None] * ab
    return np.sqrt(((pixels[:, None] - closest) ** 2).sum(-1)).min(1)


def check_overlay_pixels(width: int = 256, height: int = 192) -> None:
    """Draw the overlay of depths 1-2 into a GPUOffScreen with the camera's view: lit pixels lie on
    the box edges projected in numpy, and the projected edges are covered by lit pixels."""
    import gpu

    scene = harness.boxes_scene()
    scene.render.resolution_x, scene.render.resolution_y = width, height
    ensure_gpu_context()
    settings = scene.bvhlab
    settings.method, settings.max_leaf_size = "sah", 1
    assert bpy.ops.bvhlab.build() == {"FINISHED"}
    settings.overlay_show, settings.overlay_depth_min, settings.overlay_depth_max = True, 1, 2
    settings.overlay_color_by_depth, settings.overlay_line_width = False, 1.0
    camera = scene.camera
    depsgraph = bpy.context.evaluated_depsgraph_get()
    view_projection = camera.calc_matrix_camera(depsgraph, x=width, y=height) @ camera.matrix_world.inverted()
    offscreen = gpu.types.GPUOffScreen(width, height, format="RGBA32F")
    with offscreen.bind():
        framebuffer = gpu.state.active_framebuffer_get()
        framebuffer.clear(color=(0.0, 0.0, 0.0, 0.0))
        drawn = _overlay_package().draw_scene_overlay(scene, view_projection)
        buffer = framebuffer.read_color(0, 0, width, height, 4, 0, "FLOAT")
    offscreen.free()
    buffer.dimensions = width * height * 4  # flat first: multi-dimensional buffers read back scrambled
    image = np.asarray(buffer, np.float32).reshape(height, width, 4)  # row 0 = bottom
    bvh = harness.addon().state.tree_for(scene).bvh
    lo, hi, _ = bvh.boxes(1, 2)
    assert drawn == len(lo) == sum(bvh.stats["nodes_per_depth"][1:3])
    corners = np.stack([lo, hi], 1).astype(np.float64)  # (K, 2, 3)
    camera_model = export_scene(bpy.context).camera

    def projected(selector):  # one corner of every box: x, y, z each from min (0) or max (1)
        return _project(corners[:, list(selector), [0, 1, 2]], camera_model, width, height)

    a = np.concatenate([projected(start) for start, _ in EDGES])
    b = np.concatenate([projected(end) for _, end in EDGES])
    ys, xs = np.nonzero(image[..., 3] > 0.5)
    lit = np.stack([xs + 0.5, ys + 0.5], -1)
    assert len(lit) > 100, f"only {len(lit)} pixels drawn"
    stray = _segment_distance(lit, a, b)
    assert stray.max() < 1.5, f"{(stray >= 1.5).sum()} lit pixels are off every projected edge"
    samples = np.concatenate([a + (b - a) * t for t in np.linspace(0, 1, 200)[:, None, None]])
    inside = (samples[:, 0] > 2) & (samples[:, 0] < width - 2) & (samples[:, 1] > 2) & (samples[:, 1] < height - 2)
    covered = [image[int(y) - 1:int(y) + 2, int(x) - 1:int(x) + 2, 3].max() > 0.5 for x, y in samples[inside]]
    assert np.mean(covered) > 0.98, f"only {np.mean(covered):.3f} of the projected edges are drawn"


def check_overlay_batch_time(nodes: int = 1_000_000, budget_ms: float = 100.0) -> float:
    """The overlay batch (box table, texture, line batch) for a million boxes: best of five (the
    machine is shared; the best run is the one the code, not the neighbours, decides)."""
    ensure_gpu_context()
    batch_module = import_module(harness.addon().__name__ + ".overlay.batch")
    bvh = bvhlab.build(procedural.random_triangles((nodes + 1) // 2, seed=5), max_leaf_size=1)
    assert bvh.stats["nodes"] >= nodes - 1
    times = []
    for _ in range(5):
        start = time.perf_counter()
        batch = batch_module.BoxBatch.from_bvh(bvh)
        times.append((time.perf_counter() - start) * 1e3)
        assert batch.count == bvh.stats["nodes"]
        del batch
    best = min(times)
    print(f"overlay batch for {bvh.stats['nodes']} boxes: {best:.1f} ms (best of {times})")
    assert best <= budget_ms, f"overlay batch took {best:.1f} ms for {bvh.stats['nodes']} boxes"
    return best
