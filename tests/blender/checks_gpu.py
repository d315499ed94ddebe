"""Checks that draw with Blender's `gpu` module. Run them in their own process (Blender aborts the
process when GPU start-up fails): tests/blender/run.py --only gpu."""

from __future__ import annotations

import math
from importlib import import_module

import bpy
import harness
import numpy as np

import bvhlab
from bvhlab.blender import export_scene
from bvhlab.blender.compat import buffer_to_array
from bvhlab.library import procedural

#: The 12 edges of a box as pairs of corner selectors (0 = min, 1 = max per axis).
EDGES = (
    [((a, b, 0), (a, b, 1)) for a in (0, 1) for b in (0, 1)]
    + [((a, 0, b), (a, 1, b)) for a in (0, 1) for b in (0, 1)]
    + [((0, a, b), (1, a, b)) for a in (0, 1) for b in (0, 1)]
)


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


def _draw_offscreen(scene, width: int, height: int) -> tuple[int, np.ndarray]:
    """Draw the scene's overlay as its settings say into a GPUOffScreen with the camera's view;
    returns (boxes drawn, float32 (height, width, 4) image, row 0 at the bottom)."""
    import gpu

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
    return drawn, buffer_to_array(buffer, width, height)


def _built_boxes_scene(width: int, height: int, depth_range: tuple[int, int], **settings):
    """The three-box scene built with SAH (one triangle per leaf); the overlay must be on after
    the build by itself (nothing here ticks "Viewport Boxes")."""
    scene = harness.boxes_scene()
    scene.render.resolution_x, scene.render.resolution_y = width, height
    ensure_gpu_context()
    config = scene.bvhlab
    config.method, config.max_leaf_size = "sah", 1
    assert bpy.ops.bvhlab.build() == {"FINISHED"}
    assert config.overlay_show, "the overlay is off after Build"
    config.overlay_depth_min, config.overlay_depth_max = depth_range
    for name, value in settings.items():
        setattr(config, name, value)
    return scene, harness.addon().state.tree_for(scene).bvh


def check_overlay_pixels(width: int = 256, height: int = 192) -> None:
    """Draw the overlay of depths 1-2 into a GPUOffScreen with the camera's view: lit pixels lie on
    the box edges projected in numpy, and the projected edges are covered by lit pixels."""
    scene, bvh = _built_boxes_scene(width, height, (1, 2), overlay_line_width=1.0)
    drawn, image = _draw_offscreen(scene, width, height)
    lo, hi, _ = bvh.boxes(1, 2)
    assert drawn == len(lo) == sum(bvh.stats["nodes_per_depth"][1:3])
    a, b = _projected_edges(lo, hi, export_scene(bpy.context).camera, width, height)
    ys, xs = np.nonzero(image[..., 3] > 0.5)
    lit = np.stack([xs + 0.5, ys + 0.5], -1)
    assert len(lit) > 100, f"only {len(lit)} pixels drawn"
    stray = _segment_distance(lit, a, b)
    assert stray.max() < 1.5, f"{(stray >= 1.5).sum()} lit pixels are off every projected edge"
    samples = np.concatenate([a + (b - a) * t for t in np.linspace(0, 1, 200)[:, None, None]])
    inside = (samples[:, 0] > 2) & (samples[:, 0] < width - 2) & (samples[:, 1] > 2) & (samples[:, 1] < height - 2)
    covered = [image[int(y) - 1 : int(y) + 2, int(x) - 1 : int(x) + 2, 3].max() > 0.5 for x, y in samples[inside]]
    assert np.mean(covered) > 0.98, f"only {np.mean(covered):.3f} of the projected edges are drawn"


def _projected_edges(lo, hi, camera_model, width, height):
    """Start and end pixels (S, 2) of the 12 projected edges of every box (lo, hi: (K, 3))."""
    corners = np.stack([lo, hi], 1).astype(np.float64)  # (K, 2, 3)

    def projected(selector):  # one corner of every box: x, y, z each from min (0) or max (1)
        return _project(corners[:, list(selector), [0, 1, 2]], camera_model, width, height)

    return (
        np.concatenate([projected(start) for start, _ in EDGES]),
        np.concatenate([projected(end) for _, end in EDGES]),
    )


def check_overlay_colour_by_depth(width: int = 320, height: int = 240) -> None:
    """Colour by depth at the default range 0-3, x-ray on. Children share edges with their parents;
    where lines of several depths cover a pixel, the shallowest must win (drawn last), or the
    deepest depth's colour covers nearly every edge (the defect seen in Blender). Checked against
    the box edges projected in numpy: every lit pixel clearly on one depth's edges and off the
    shallower depths' has that depth's colour (from the core's palette), and every depth of the
    range owns lit pixels."""
    scene, bvh = _built_boxes_scene(
        width, height, (0, 3), overlay_color_by_depth=True, overlay_xray=True, overlay_line_width=1.0
    )
    assert bvh.stats["height"] > 4, "the scene must be deeper than the range"
    drawn, image = _draw_offscreen(scene, width, height)
    assert drawn == sum(bvh.stats["nodes_per_depth"][0:4])
    palette = bvhlab._core.depth_colors(np.arange(4, dtype=np.uint32))
    ys, xs = np.nonzero(image[..., 3] > 0.5)
    rgb = image[ys, xs, :3]
    distance_to_colour = np.linalg.norm(rgb[:, None, :] - palette[None], axis=-1)  # (pixels, depths)
    assert distance_to_colour.min(1).max() < 0.02, "a lit pixel has no depth's colour"
    colour_depth = distance_to_colour.argmin(1)
    camera_model = export_scene(bpy.context).camera
    centres = np.stack([xs + 0.5, ys + 0.5], -1)
    to_depth = np.stack(
        [
            _segment_distance(centres, *_projected_edges(*bvh.boxes(d, d)[:2], camera_model, width, height))
            for d in range(4)
        ],
        1,
    )
    # A 1-pixel line lights the pixels whose centres lie within about half a pixel of it; between
    # 0.4 and 1.5 pixels away a pixel may or may not be lit, so a depth there makes it ambiguous.
    on, off = to_depth < 0.4, to_depth > 1.5  # clearly on a line / clearly away from one
    expected = np.where(on.any(1), on.argmax(1), -1)  # the shallowest depth whose line covers it
    clear = (expected >= 0) & np.array([off[i, : expected[i]].all() for i in range(len(expected))])
    agreement = (colour_depth[clear] == expected[clear]).mean()
    counts = np.bincount(colour_depth, minlength=4)
    print(
        f"colour by depth 0-3: {counts.tolist()} pixels per depth; {agreement:.3f} of {clear.sum()} "
        f"unambiguous pixels have the shallowest covering depth's colour"
    )
    assert clear.sum() > 200 and agreement > 0.99, f"only {agreement:.3f} of the pixels show the right depth"
    assert counts.min() >= 20, f"a depth is hardly visible: pixels per depth {counts.tolist()}"


def check_overlay_colour_by_measure(width: int = 320, height: int = 240) -> None:
    """Colour by a measure (leaves only, coloured by the primitives under each): before the tree is
    analysed the boxes keep the depth colours (drawing never computes node data); after Analyse
    Tree every lit pixel has the heat-ramp colour of one drawn leaf's value, several leaf sizes show,
    and the panel's legend is the table's."""
    from bvhlab.inspect.measures import box_order, measure_values

    scene, bvh = _built_boxes_scene(
        width, height, (0, 40), overlay_leaves_only=True, overlay_xray=True, overlay_line_width=1.0
    )
    scene.bvhlab.max_leaf_size = 4
    assert bpy.ops.bvhlab.build() == {"FINISHED"}
    bvh = harness.addon().state.tree_for(scene).bvh
    scene.bvhlab.overlay_measure = "leaf_size"
    _, before = _draw_offscreen(scene, width, height)
    palette = bvhlab._core.depth_colors(np.arange(64, dtype=np.uint32))
    lit = before[before[..., 3] > 0.5][:, :3]
    assert len(lit) > 200 and np.linalg.norm(lit[:, None] - palette[None], axis=-1).min(1).max() < 0.02
    assert bpy.ops.bvhlab.analyse_tree() == {"FINISHED"}
    drawn, image = _draw_offscreen(scene, width, height)
    data = bvh.cached_node_data()
    order = box_order(data, leaves_only=True)
    values, legend = measure_values(data, "leaf_size", order)
    assert drawn == len(order)
    colours = bvhlab._core.heat_colors(np.unique(values))
    lit = image[image[..., 3] > 0.5][:, :3]
    distance = np.linalg.norm(lit[:, None] - colours[None], axis=-1)
    nearest = distance.argmin(1)
    print(f"colour by leaf size: {len(lit)} lit pixels, {len(colours)} values, legend {legend.text()}")
    assert distance.min(1).max() < 0.02, "a lit pixel has no drawn leaf's ramp colour"
    assert len(np.unique(nearest)) >= 2, "only one leaf size is visible"
    assert legend.high == data.prim_count[order].max()


def check_overlay_million_boxes(nodes: int = 1_000_000) -> None:
    """The overlay batch of a million-node tree: every box uploaded (several texture rows), and
    each depth range is the slice the tree's per-depth counts say. (Its time is measured in
    bench/blender_export.py.)"""
    ensure_gpu_context()
    batch_module = import_module(harness.addon().__name__ + ".overlay.batch")
    bvh = bvhlab.build(procedural.random_triangles((nodes + 1) // 2, seed=5), max_leaf_size=1)
    stats = bvh.stats
    assert stats["nodes"] >= nodes - 1
    batch = batch_module.BoxBatch.from_bvh(bvh)
    assert batch.count == stats["nodes"] and batch.texture.height > 1
    for depth_min, depth_max in ((0, 0), (5, 9), (stats["height"] - 1, stats["height"] - 1)):
        first, count = batch.table.depth_slice(depth_min, depth_max)
        assert first == sum(stats["nodes_per_depth"][:depth_min])
        assert count == sum(stats["nodes_per_depth"][depth_min : depth_max + 1])


def _scatter_scene(width: int, height: int, side: int, cube: float):
    """side × side geometry-nodes instances (Grid 4 × 2 → Instance on Points) of a cube of edge
    `cube` with 10 × 10 vertices a face (a BLAS of some hundred nodes), seen by a camera."""
    scene = harness.empty_scene((width, height))
    tree = bpy.data.node_groups.new("Scatter", "GeometryNodeTree")
    tree.interface.new_socket("Geometry", in_out="OUTPUT", socket_type="NodeSocketGeometry")
    output, grid = tree.nodes.new("NodeGroupOutput"), tree.nodes.new("GeometryNodeMeshGrid")
    grid.inputs["Size X"].default_value, grid.inputs["Size Y"].default_value = 4.0, 2.0
    grid.inputs["Vertices X"].default_value = grid.inputs["Vertices Y"].default_value = side
    mesh = tree.nodes.new("GeometryNodeMeshCube")
    mesh.inputs["Size"].default_value = (cube,) * 3
    for axis in "XYZ":
        mesh.inputs[f"Vertices {axis}"].default_value = 10
    instance = tree.nodes.new("GeometryNodeInstanceOnPoints")
    tree.links.new(grid.outputs["Mesh"], instance.inputs["Points"])
    tree.links.new(mesh.outputs["Mesh"], instance.inputs["Instance"])
    tree.links.new(instance.outputs["Instances"], output.inputs[0])
    obj = bpy.data.objects.new("Scatter", bpy.data.meshes.new("Scatter"))
    scene.collection.objects.link(obj)
    obj.modifiers.new("Scatter", "NODES").node_group = tree
    harness.add_camera((0.0, -6.0, 4.0), (0.0, 0.0, 0.0), lens=35)
    harness.add_point_light((2.0, -3.0, 5.0))
    bpy.context.view_layer.update()
    xs, ys = np.linspace(-2, 2, side), np.linspace(-1, 1, side)
    centres = np.stack(np.meshgrid(xs, ys, [0.0], indexing="ij"), -1).reshape(-1, 3)
    return scene, centres


def check_overlay_two_level_boxes(width: int = 256, height: int = 192, side: int = 100) -> None:
    """The overlay of a two-level tree (issue 34): 10,000 geometry-nodes instances, built by
    Build. BLAS boxes are capped at MAX_OVERLAY_BOXES (the panel's note says how many instances),
    TLAS boxes are drawn in full, and the TLAS root drawn alone lights the projected edges of the
    union of the cubes placed at the grid points computed here (not by bvhlab)."""
    cube = 0.02
    scene, centres = _scatter_scene(width, height, side, cube)
    ensure_gpu_context()
    addon = harness.addon()
    levels = import_module(addon.__name__ + ".overlay.levels")
    assert bpy.ops.bvhlab.build() == {"FINISHED"}
    bvh = addon.state.tree_for(scene).bvh
    assert isinstance(bvh, bvhlab.InstancedBvh) and bvh.stats["instances"] == side * side
    settings = scene.bvhlab
    settings.overlay_level, settings.overlay_depth_min, settings.overlay_depth_max = "blas", 0, 20
    drawn, _ = _draw_offscreen(scene, width, height)
    mesh_of, _ = bvh.instances
    per_instance = len(bvh.meshes[int(mesh_of[0])].boxes(0, 20)[0])
    assert np.all(mesh_of == mesh_of[0]) and per_instance * side * side > levels.MAX_OVERLAY_BOXES
    assert drawn == levels.MAX_OVERLAY_BOXES // per_instance * per_instance, (drawn, per_instance)
    note = _overlay_package().scene_batch(scene, addon.state.tree_for(scene)).table.note
    assert f"of {side * side:,} instances" in note, note
    settings.overlay_level = "tlas"
    drawn, _ = _draw_offscreen(scene, width, height)
    assert drawn == bvh.stats["tlas_nodes"] > side * side
    settings.overlay_depth_max = 0
    drawn, image = _draw_offscreen(scene, width, height)
    assert drawn == 1
    lo, hi = centres.min(0) - cube / 2, centres.max(0) + cube / 2
    a, b = _projected_edges(lo[None], hi[None], export_scene(bpy.context).camera, width, height)
    ys, xs = np.nonzero(image[..., 3] > 0.5)
    assert len(xs) > 50, f"only {len(xs)} pixels drawn"
    stray = _segment_distance(np.stack([xs + 0.5, ys + 0.5], -1), a, b)
    assert stray.max() < 1.5, f"{(stray >= 1.5).sum()} lit pixels are off the root box's projected edges"
