"""The render engine "bvhlab Whitted" under Blender's own render pipeline (bpy.ops.render.render, as
F12 and `blender -b` run it): the passes read back from a multilayer EXR Blender wrote (read by
tests/blender/exr.py, not by Blender), against the CPU reference tracer on the same export, a
brute-force depth and Bvh.intersect's box-test counts; what a re-render reads again (animation
frames: checks_engine_frames.py). The add-on must be enabled (harness.enable_addon_from_source or
an installed zip)."""

from __future__ import annotations

import math

import bpy
import exr
import harness
import numpy as np

import bvhlab
import bvhlab.counters
from bvhlab.blender import export_scene
from bvhlab.blender.compat import use_multilayer_exr

ENGINE = "BVHLAB_WHITTED"
#: Blender's value for "no surface" in a Depth pass (render_result.cc fills passes named Depth with it).
MISS_DEPTH = float(np.float32(bvhlab._core.NO_DEPTH))  # what the tracer (and Cycles) write where nothing is hit


def _records():
    return harness.addon().state


def _last_final(scene=None) -> dict:
    scene = scene or bpy.context.scene
    return _records().last_final[scene.session_uid]


def use_engine(scene, **settings):
    """Select the engine on `scene`, with the Depth pass and the given scene.bvhlab settings."""
    scene.render.engine = ENGINE
    bpy.context.view_layer.use_pass_z = True
    for name, value in settings.items():
        setattr(scene.bvhlab, name, value)


def render_passes(tmp_dir, name: str = "render") -> dict:
    """F12 (bpy.ops.render.render), then the Render Result saved as a 32-bit multilayer EXR without
    compression; returns {pass name: top-row-first float32 array} for the first view layer."""
    assert bpy.ops.render.render() == {"FINISHED"}
    settings = bpy.context.scene.render.image_settings
    use_multilayer_exr(settings)
    settings.exr_codec, settings.color_depth = "NONE", "32"
    path = tmp_dir / f"{name}.exr"
    # Blender 5.0 writes no multilayer EXR of a render whose pixel aspect is not 1 ("Conflicting
    # attributes found for header :: ViewLayer.Depth 'pixelAspectRatio'", Cycles' renders too):
    # the aspect is only the file's header attribute, so save with 1 (the pixels are the same).
    render = bpy.context.scene.render
    aspect = render.pixel_aspect_x, render.pixel_aspect_y
    render.pixel_aspect_x = render.pixel_aspect_y = 1.0
    try:
        bpy.data.images["Render Result"].save_render(str(path))
    finally:
        render.pixel_aspect_x, render.pixel_aspect_y = aspect
    channels = exr.read_exr(path)
    layer = bpy.context.view_layer.name
    out = {}
    counter_passes = [(f"BVH {bvhlab.counters.LABELS[c].title()}", "X") for c in bvhlab.counters.COUNTERS]
    for pass_name, ids in (("Combined", "RGBA"), ("Depth", "Z"), ("BVH Heatmap", "RGBA"), *counter_passes):
        names = [f"{layer}.{pass_name}.{c}" for c in ids]
        if all(n in channels for n in names):
            out[pass_name] = np.stack([channels[n] for n in names], -1) if len(ids) > 1 else channels[names[0]]
    return out


def reference(scene, samples_per_axis: int, overlay=None, mode="shade", exported=None, **build):
    """bvhlab.render on the CPU reference of a fresh export (or of `exported`), tree built
    directly: the oracle."""
    exported = export_scene(bpy.context) if exported is None else exported
    settings = scene.bvhlab
    bvh = bvhlab.build(exported, config=settings.build_config(), **build)
    width, height = scene.render.resolution_x, scene.render.resolution_y
    image, _ = bvhlab.render(
        exported,
        bvh,
        width,
        height,
        backend="cpu",
        samples_per_axis=samples_per_axis,
        max_depth=settings.render_bounces,
        overlay_depth=overlay,
        traversal=settings.traversal,
        mode=mode,
        color_by_depth=settings.overlay_color_by_depth,
        line_width=settings.overlay_line_width,
        film_transparent=scene.render.film_transparent,
    )
    return image, exported, bvh


def compare_images(ours: np.ndarray, oracle: np.ndarray, backend: str) -> None:
    """Exactly equal on the CPU reference (same code, same inputs); on a GPU, or for scenes laid
    out otherwise (an object as an instance against the same object placed in the world: the
    rays moved into its space round otherwise), within the tolerance of
    tests/python/test_render_vulkan.py."""
    diff = np.abs(ours - oracle)
    if backend == "cpu":
        assert diff.max() == 0.0, f"differs from the CPU reference by up to {diff.max()}"
    else:
        assert diff.mean() <= 1e-3 and (diff.max(-1) > 1e-3).mean() <= 0.01, (diff.mean(), diff.max())


def check_engine_selectable() -> None:
    """The engine is a RenderEngine Blender lists; Blender's own output panels and the material
    surface panel show for it."""
    assert ENGINE in {getattr(cls, "bl_idname", None) for cls in bpy.types.RenderEngine.__subclasses__()}
    scene = harness.boxes_scene()
    scene.render.engine = ENGINE
    assert scene.render.engine == ENGINE
    for panel in (
        "RENDER_PT_format",
        "RENDER_PT_output",
        "RENDER_PT_frame_range",
        "DATA_PT_lens",
        "DATA_PT_light",
        "EEVEE_MATERIAL_PT_surface",
    ):
        assert ENGINE in getattr(bpy.types, panel).COMPAT_ENGINES, panel


def check_combined_and_heatmap_match_the_tracer(tmp_dir) -> None:
    """Whitted scene (mirror, glass, analytic spheres), 2×2 samples, 5 bounces, boxes of depths 1-3
    in the image, backend auto: Combined and BVH Heatmap equal bvhlab.render of the exported
    scene from the same camera (the CPU reference; exactly, when auto rendered on the CPU)."""
    scene = harness.open_scene("whitted")
    scene.render.resolution_x, scene.render.resolution_y, scene.render.resolution_percentage = 160, 120, 100
    use_engine(
        scene,
        backend="auto",
        render_supersampling=2,
        render_bounces=5,
        render_overlay=True,
        overlay_depth_min=1,
        overlay_depth_max=3,
        traversal="stackless",
    )
    bpy.context.view_layer.bvhlab_use_pass_heatmap = True  # off by default (the file opened next resets it)
    got = render_passes(tmp_dir)
    record = _last_final(scene)
    combined, _, _ = reference(scene, samples_per_axis=2, overlay=(1, 3))
    heat, _, _ = reference(scene, samples_per_axis=2, overlay=(1, 3), mode="heatmap")
    assert got["Combined"].shape == (120, 160, 4)
    compare_images(got["Combined"], combined, record["backend"])
    compare_images(got["BVH Heatmap"], heat, record["backend"])
    sky = np.abs(combined[..., :3] - np.array(export_scene(bpy.context).sky)).max(-1) < 1e-6
    assert 0.1 < sky.mean() < 0.9, "the picture must show both geometry and sky"
    print(f"engine: whitted 160×120, 4 spp on {record['device']} ({record['backend']}); {record.get('note')}")


def check_wide_traversal_renders_the_stack_image(tmp_dir) -> None:
    """Traversal ▸ Wide (CPU): F12 through the tree's 8-wide copy gives the stack walk's Combined and
    Depth, bit for bit where both rendered on the CPU (whitted: glass, whose shadow rays the stack
    walk answers, mirrors, analytic spheres; 2×2 samples); backend auto renders it on the CPU."""
    scene = harness.open_scene("whitted")
    scene.render.resolution_x, scene.render.resolution_y, scene.render.resolution_percentage = 96, 72, 100
    use_engine(scene, backend="auto", render_supersampling=2, render_bounces=5, render_overlay=False, traversal="stack")
    stack = render_passes(tmp_dir, "stack")
    stack_backend = _last_final(scene)["backend"]
    scene.bvhlab.traversal = "wide"
    wide = render_passes(tmp_dir, "wide")
    record = _last_final(scene)
    assert record["backend"] == "cpu" and "wide walk" in record["device"], record
    compare_images(wide["Combined"], stack["Combined"], stack_backend)
    if stack_backend == "cpu":
        assert np.array_equal(wide["Depth"], stack["Depth"])
    hit = stack["Depth"] < MISS_DEPTH
    assert 0.1 < hit.mean() < 0.95, hit.mean()


def check_auto_traversal_renders_wide_on_the_cpu_and_stack_for_the_heatmap_pass(tmp_dir) -> None:
    """Traversal ▸ Auto, the default: F12 on the CPU walks the wide trees (the stack walk's Combined
    and Depth bit for bit); with the view layer's heatmap pass on (off by default), the stack walk,
    so the pass is the binary tree's box tests (the stack F12's pass, bit for bit), as the heatmap
    mode shows."""
    scene = harness.open_scene("whitted")
    scene.render.resolution_x, scene.render.resolution_y, scene.render.resolution_percentage = 96, 72, 100
    assert scene.bvhlab.traversal == "auto", scene.bvhlab.traversal  # a scene saved before Auto: the default
    assert not bpy.context.view_layer.bvhlab_use_pass_heatmap
    use_engine(scene, backend="cpu", render_supersampling=2, render_bounces=5, render_overlay=False)
    auto = render_passes(tmp_dir, "auto")
    assert "wide walk" in _last_final(scene)["device"], _last_final(scene)
    scene.bvhlab.traversal = "stack"
    stack = render_passes(tmp_dir, "stack")
    assert np.array_equal(auto["Combined"], stack["Combined"]) and np.array_equal(auto["Depth"], stack["Depth"])
    bpy.context.view_layer.bvhlab_use_pass_heatmap = True
    try:
        stack_heat = render_passes(tmp_dir, "stack_heat")
        scene.bvhlab.traversal = "auto"
        auto_heat = render_passes(tmp_dir, "auto_heat")
    finally:
        bpy.context.view_layer.bvhlab_use_pass_heatmap = False
    assert "wide walk" not in _last_final(scene)["device"], _last_final(scene)
    assert np.array_equal(auto_heat["BVH Heatmap"], stack_heat["BVH Heatmap"])
    assert np.array_equal(auto_heat["Combined"], auto["Combined"])


def check_film_transparent_gives_the_share_of_camera_rays_as_alpha(tmp_dir) -> None:
    """Render Properties ▸ Film ▸ Transparent: F12's Combined alpha is the share of each pixel's
    camera rays that show something (the CPU reference's with film_transparent, bit for bit on the
    CPU; 0 where only the sky is seen, quarters at silhouettes at 2×2 samples), its colour
    premultiplied; the Depth pass is the opaque render's. Off, every pixel is opaque. (The
    viewport's: checks_engine_viewport.)"""
    scene = harness.open_scene("whitted")
    scene.render.resolution_x, scene.render.resolution_y, scene.render.resolution_percentage = 64, 48, 100
    use_engine(scene, backend="cpu", render_supersampling=2, render_bounces=5, render_overlay=False)
    opaque = render_passes(tmp_dir, "opaque")
    assert np.all(opaque["Combined"][..., 3] == 1.0)
    scene.render.film_transparent = True
    film = render_passes(tmp_dir, "film")
    exported = export_scene(bpy.context)
    bvh = bvhlab.build(exported, config=scene.bvhlab.build_config())
    options = scene.bvhlab.render_options()
    assert options.film_transparent
    expected, _ = bvhlab.render(exported, bvh, 64, 48, backend="cpu", options=options)
    np.testing.assert_array_equal(film["Combined"], expected)
    alpha = film["Combined"][..., 3]
    assert (alpha == 0).any() and (alpha == 1).any() and ((alpha > 0) & (alpha < 1)).any()
    assert np.all(film["Combined"][..., :3] <= opaque["Combined"][..., :3] + 1e-6)
    np.testing.assert_array_equal(film["Depth"], opaque["Depth"])


def check_final_render_shows_what_renders_not_what_the_viewport_shows(tmp_dir) -> None:
    """F12 renders what Blender renders: an object hidden in the viewport (the eye, or Disable in
    Viewports) is in the image, as in Cycles, and one disabled in renders is not; an export from
    the viewport's depsgraph (the sidebar, the Rendered viewport) keeps to what the viewport shows."""
    scene = harness.boxes_scene()
    scene.render.resolution_x, scene.render.resolution_y, scene.render.resolution_percentage = 32, 24, 100
    use_engine(scene, backend="cpu", render_overlay=False)
    boxes = sorted((o for o in scene.objects if o.type == "MESH"), key=lambda o: o.name)
    each = len(boxes[0].data.polygons) * 2  # triangles of one box (quads)

    def rendered() -> int:
        render_passes(tmp_dir, "visibility")
        return len(_last_final(scene)["scene"].triangles)

    everything = rendered()
    assert everything == each * len(boxes), everything
    boxes[0].hide_set(True)
    boxes[1].hide_viewport = True
    boxes[2].hide_render = True
    bpy.context.view_layer.update()
    assert rendered() == everything - each  # only the one disabled in renders is gone
    # the viewport shows only the one disabled in renders
    assert len(export_scene(bpy.context, scope="visible").triangles) == everything - 2 * each
    boxes[2].hide_render = False
    assert rendered() == everything


def check_an_object_in_edit_mode_is_rendered_with_its_edits(tmp_dir) -> None:
    """A mesh in Edit Mode is in F12 and in the sidebar's tree, with the edits made so far, as
    Cycles renders it (its evaluated data is Blender's wrapper of the edit mesh, without polygons
    until converted: it was left out without a word). Its image is the one F12 gives once the edit
    is applied in Object Mode, bit for bit."""
    import bmesh

    scene = harness.boxes_scene()
    scene.render.resolution_x, scene.render.resolution_y, scene.render.resolution_percentage = 32, 24, 100
    use_engine(scene, backend="cpu", render_overlay=False)
    box = bpy.data.objects["Box A"]
    everything = sum(len(o.data.polygons) * 2 for o in scene.objects if o.type == "MESH")
    before = render_passes(tmp_dir, "object_mode")["Depth"]
    bpy.context.view_layer.objects.active = box
    bpy.ops.object.mode_set(mode="EDIT")
    try:
        edit = bmesh.from_edit_mesh(box.data)
        for vertex in edit.verts:
            vertex.co.z += 0.6  # up by most of its height: its silhouette moves
        bmesh.update_edit_mesh(box.data)
        in_edit = render_passes(tmp_dir, "edit_mode")["Depth"]
        assert len(_last_final(scene)["scene"].triangles) == everything
        assert bpy.ops.bvhlab.build() == {"FINISHED"}
        assert harness.addon().state.tree_for(scene).bvh.stats["primitives"] == everything
    finally:
        bpy.ops.object.mode_set(mode="OBJECT")
    assert not np.array_equal(in_edit, before)  # the edit shows
    np.testing.assert_array_equal(in_edit, render_passes(tmp_dir, "applied")["Depth"])


def check_final_render_takes_blenders_render_threads(tmp_dir) -> None:
    """F12 and the sidebar's Render trace on Render Properties ▸ Performance ▸ Threads, as Cycles
    does (Fixed: that many; Auto-detect: Blender's count, every core; `blender -t N` sets the
    same count): the job says how many, and the image is the same on 1 and 3 threads."""
    scene = harness.open_scene("whitted")
    scene.render.resolution_x, scene.render.resolution_y, scene.render.resolution_percentage = 64, 48, 100
    use_engine(scene, backend="cpu", render_supersampling=2, render_overlay=False)
    scene.render.threads_mode = "FIXED"
    images = {}
    for n, said in ((1, "(1 thread,"), (3, "(3 threads,")):
        scene.render.threads = n
        images[n] = render_passes(tmp_dir, f"threads_{n}")["Combined"]
        assert said in _last_final(scene)["device"], (n, _last_final(scene)["device"])
        assert bpy.ops.bvhlab.render() == {"FINISHED"}
        sidebar = harness.addon().state.last_render[harness.addon().state.key(scene)]["device"]
        assert said in sidebar, (n, sidebar)
    assert np.array_equal(images[1], images[3])
    scene.render.threads_mode = "AUTO"
    said = f"({scene.render.threads} thread"
    render_passes(tmp_dir, "threads_auto")
    assert said in _last_final(scene)["device"], (said, _last_final(scene)["device"])


def heat_color(x: np.ndarray) -> np.ndarray:
    """shaders/tracer/shade_colors.glsl heat_color, in numpy."""
    t = np.clip(x, 0.0, 1.0)[..., None]
    return np.clip(1.5 - np.abs(4.0 * t - np.array([3.0, 2.0, 1.0])), 0.0, 1.0)


def _ulp_neighbours(direction: np.ndarray) -> np.ndarray:
    """The 27 float32 directions whose components are `direction`'s or its next float either way."""
    steps = [
        np.array([np.nextafter(c, np.float32(-np.inf)), c, np.nextafter(c, np.float32(np.inf))]) for c in direction
    ]
    grid = np.meshgrid(*steps, indexing="ij")
    return np.ascontiguousarray(np.stack([g.ravel() for g in grid], 1), np.float32)


def check_heatmap_is_box_tests(tmp_dir) -> None:
    """At one sample per pixel the heatmap pass is heat_color(box tests / (8 × tree height)) of the
    primary rays, the box tests counted by Bvh.intersect (the core's traversal, not the tracer's).
    The rays are worked out here in another order of float operations than the tracer's, so a ray
    through a box's face or along a shared edge may differ by an ulp and take another path: at most
    one pixel in a thousand may differ, and each such pixel's colour must be the box tests of a ray
    whose direction is within one ulp of this one's in each component (Sponza and suzanne_250k's
    default trees gave pixels 4 and 8 box tests apart that way)."""
    scene = harness.open_scene("suzanne_250k")
    scene.render.resolution_x, scene.render.resolution_y, scene.render.resolution_percentage = 96, 72, 100
    use_engine(scene, backend="cpu", render_supersampling=1, render_overlay=False, traversal="stack")
    bpy.context.view_layer.bvhlab_use_pass_heatmap = True
    got = render_passes(tmp_dir)
    exported = export_scene(bpy.context)
    s = scene.bvhlab  # the tree the engine builds: the panel's settings
    bvh = bvhlab.build(exported, config=s.build_config())
    directions = _primary_directions(exported.camera, 96, 72)
    origins = np.ascontiguousarray(np.broadcast_to(np.float32(exported.camera.position), directions.shape))
    visited = bvh.intersect(origins, directions, traversal="stack", nodes_visited=True)["nodes_visited"].reshape(72, 96)
    scale = 8.0 * bvh.stats["height"]
    expected = heat_color(visited / scale)
    off = np.abs(got["BVH Heatmap"][..., :3] - expected).max(-1) > 1e-6
    assert off.mean() <= 1e-3, f"{off.sum()} pixels differ"
    for y, x in zip(*np.nonzero(off)):
        nudged = _ulp_neighbours(directions[y * 96 + x])
        counts = bvh.intersect(origins[: len(nudged)], nudged, traversal="stack", nodes_visited=True)["nodes_visited"]
        candidates = heat_color(counts / scale)
        assert np.abs(candidates - got["BVH Heatmap"][y, x, :3]).max(-1).min() <= 1e-6, (y, x, visited[y, x])
    assert len(np.unique(visited)) > 10, "the heatmap must vary over the picture"


def check_counter_passes_are_the_cpu_counters(tmp_dir) -> None:
    """With the view layer's BVH Counters on, F12 writes one float pass per traversal counter: the
    counts per primary ray of the CPU reference on the same export and tree (2×2 samples, mirror
    and glass: the secondary rays are not counted), exactly."""
    scene = harness.open_scene("whitted")
    scene.render.resolution_x, scene.render.resolution_y, scene.render.resolution_percentage = 64, 48, 100
    use_engine(scene, backend="cpu", render_supersampling=2, render_bounces=5, render_overlay=False)
    bpy.context.view_layer.bvhlab_use_pass_counters = True
    try:
        got = render_passes(tmp_dir)
    finally:
        bpy.context.view_layer.bvhlab_use_pass_counters = False
    exported = export_scene(bpy.context)
    bvh = bvhlab.build(exported, config=scene.bvhlab.build_config())
    options = scene.bvhlab.render_options().replace(traversal_counters=True)
    job = bvhlab.Renderer("cpu").start(exported, bvh, 64, 48, options=options)
    job.run()
    expected = job.result(color=False, depth=False, cost=False, counters=True).counters
    for k, counter in enumerate(bvhlab.counters.COUNTERS):
        name = f"BVH {bvhlab.counters.LABELS[counter].title()}"
        assert name in got, f"no {name} pass in {sorted(got)}"
        np.testing.assert_array_equal(got[name], expected[..., k], err_msg=name)
    assert got["BVH Box Tests"].max() > got["BVH Box Hits"].max() > 0 and got["BVH Primitive Tests"].max() > 0
    print(f"counter passes: box tests up to {got['BVH Box Tests'].max():g} per primary ray")


def _primary_directions(camera, width: int, height: int, samples_per_axis: int = 1) -> np.ndarray:
    """Directions with unit component along the view axis through the n×n sample positions of
    every pixel ((sx + 0.5) / n across the pixel, as the tracer places them), pixel by pixel, row 0
    at the top: (height·width·n², 3). At n = 1, the pixel centres. Written here again, not taken
    from the engine or the tracer."""
    position, look_at, up = (np.array(v, np.float64) for v in (camera.position, camera.look_at, camera.up))
    forward = (look_at - position) / np.linalg.norm(look_at - position)
    right = np.cross(forward, up)
    right /= np.linalg.norm(right)
    true_up = np.cross(right, forward)
    tan = math.tan(math.radians(camera.fov_y) / 2)
    n = samples_per_axis
    offsets = (np.arange(n) + 0.5) / n
    xs = (((np.arange(width)[:, None] + offsets[None]) / width * 2 - 1) * tan * width / height).reshape(-1)
    ys = ((1 - (np.arange(height)[:, None] + offsets[None]) / height * 2) * tan).reshape(-1)
    d = forward + xs[None, :, None] * right + ys[:, None, None] * true_up  # (height·n, width·n, 3)
    d = d.reshape(height, n, width, n, 3).transpose(0, 2, 1, 3, 4)
    return np.ascontiguousarray(d.reshape(-1, 3), np.float32)


def brute_force_depth(exported, width: int, height: int, samples_per_axis: int = 1) -> np.ndarray:
    """Camera-space depth of the nearest triangle or sphere over each pixel's n×n sample rays,
    testing every primitive (Möller-Trumbore; the sphere quadratic), float64; MISS_DEPTH for none."""
    directions = _primary_directions(exported.camera, width, height, samples_per_axis).astype(np.float64)
    origin = np.array(exported.camera.position, np.float64)
    best = np.full(len(directions), np.inf)
    tris = exported.triangles.astype(np.float64)
    for chunk in np.array_split(np.arange(len(tris)), max(1, len(tris) // 64)):
        a, b, c = tris[chunk, 0], tris[chunk, 1], tris[chunk, 2]
        e1, e2 = b - a, c - a
        p = np.cross(directions[:, None], e2[None])
        det = (p * e1[None]).sum(-1)
        inv = 1.0 / np.where(np.abs(det) < 1e-12, np.nan, det)
        s = origin - a
        u = (p * s[None]).sum(-1) * inv
        q = np.cross(s, e1)
        v = (directions @ q.T) * inv
        t = (e2 * q).sum(-1)[None] * inv
        hit = (u >= 0) & (v >= 0) & (u + v <= 1) & (t > 1e-6)
        best = np.minimum(best, np.where(hit, t, np.inf).min(1))
    for cx, cy, cz, r in exported.spheres.astype(np.float64):
        oc = origin - (cx, cy, cz)
        a2, b2, c2 = (directions**2).sum(1), 2 * directions @ oc, oc @ oc - r * r
        disc = b2 * b2 - 4 * a2 * c2
        t = (-b2 - np.sqrt(np.maximum(disc, 0))) / (2 * a2)
        best = np.minimum(best, np.where((disc >= 0) & (t > 1e-6), t, np.inf))
    best = best.reshape(height, width, samples_per_axis**2).min(-1)
    return np.where(np.isfinite(best), best, MISS_DEPTH)


def check_depth_is_camera_z(tmp_dir) -> None:
    """Depth pass = distance along the view axis to the nearest surface over each pixel's 2×2
    sample rays (Blender's Z pass; 1e10, what Cycles writes, where nothing is hit), against a
    brute-force test of every triangle and sphere."""
    scene = harness.open_scene("whitted")
    scene.render.resolution_x, scene.render.resolution_y, scene.render.resolution_percentage = 80, 60, 100
    use_engine(scene, backend="cpu", render_supersampling=2, render_overlay=False)
    depth = render_passes(tmp_dir)["Depth"]
    expected = brute_force_depth(export_scene(bpy.context), 80, 60, samples_per_axis=2)
    hit = expected < MISS_DEPTH
    assert 0.2 < hit.mean() < 0.95
    agree = np.where(hit, np.abs(depth - expected) <= 1e-4 * expected, depth == np.float32(MISS_DEPTH))
    assert agree.mean() >= 0.995, f"only {agree.mean():.4f} of the pixels have the brute-force depth"


def _principled(name: str, color):
    from bvhlab.blender.compat import ensure_shader_tree

    material = bpy.data.materials.new(name)
    ensure_shader_tree(material).nodes["Principled BSDF"].inputs["Base Color"].default_value = (*color, 1.0)
    return material


def check_rerender_reads_only_what_changed(tmp_dir) -> None:
    """Persistent Data on (Blender keeps the engine and its depsgraph between renders): a changed
    material reaches the next render with no object read again (5.3: its object, below), a moved
    object is placed again (no read; on its first move it gets a mesh and an instance of its own,
    so mesh 0's tree and its own are built once, and a second move makes a new TLAS only), an
    edited mesh is read again (on its first edit it too gets a mesh of its own: both trees built
    once; at its second, its own tree is refit); every render equals bvhlab.render of a full
    export. Off: every render exports everything (the box, not animated, is in mesh 0 again: built
    once), and the tree is then kept."""
    scene = harness.boxes_scene()
    box = bpy.data.objects["Box A"]
    box.data.materials.append(_principled("Paint", (0.8, 0.1, 0.1)))
    use_engine(scene, backend="cpu", render_supersampling=1, render_overlay=False)
    scene.render.use_persistent_data = True
    steps = [
        ("first", None),
        ("material", lambda: _set_color("Paint", (0.1, 0.8, 0.1))),
        ("move", lambda: setattr(bpy.data.objects["Box B"], "location", (1.0, 0.3, 0.9))),
        ("move again", lambda: setattr(bpy.data.objects["Box B"], "location", (1.2, 0.3, 0.8))),
        ("edit", lambda: _move_vertex("Box C")),
        ("edit again", lambda: _move_vertex("Box C")),
        ("nothing", None),
    ]
    seen, images = [], []
    for step, change in steps:
        if change:
            change()
        images.append(render_passes(tmp_dir, step)["Combined"])
        record = _last_final(scene)
        totals = record["totals"]
        seen.append(
            (step, totals.full_syncs, totals.objects_read, totals.objects_moved, totals.materials_read, record["tree"])
        )
        # exactly its own scene over a fresh tree; a full export (which has the moved box, not
        # animated, in mesh 0) within float rounding
        compare_images(images[-1], reference(scene, samples_per_axis=1, exported=record["scene"])[0], "cpu")
        compare_images(
            images[-1], reference(scene, samples_per_axis=1)[0], "cpu" if step in ("first", "material") else "layout"
        )
    print(f"engine re-renders (step, full exports, objects read, moved, materials read, tree): {seen}")
    # materials: the empty slot's default and "Paint" at first; the moved box becomes a mover
    # (docs/design.md, "Blender's instancing"), and so does the edited box; edited again, it keeps
    # its triangle count and order, so its own tree is refit. Blender 5.3 flags the object of a changed material as a
    # geometry update (5.2 as shading only): it is read again, found the same, and the tree kept.
    again = 1 if bpy.app.version >= (5, 3, 0) else 0
    assert [row[1:] for row in seen] == [
        (1, 3, 0, 2, "built"),
        (1, 3 + again, 0, 3, "kept"),
        (1, 3 + again, 1, 3, "built"),
        (1, 3 + again, 2, 3, "placed"),
        (1, 4 + again, 2, 3, "built"),
        (1, 5 + again, 2, 3, "refit"),
        (1, 5 + again, 2, 3, "kept"),
    ], seen
    assert np.abs(images[1] - images[0]).max() > 0.1, "the new colour did not reach the render"
    scene.render.use_persistent_data = False
    render_passes(tmp_dir, "fresh")
    record = _last_final(scene)
    # a fresh export has not seen the box move: it is back in mesh 0 (a new layout, built once)
    assert record["totals"].full_syncs == 1 and record["tree"] == "built", record
    render_passes(tmp_dir, "fresh again")
    record = _last_final(scene)
    assert record["totals"].full_syncs == 1 and record["tree"] == "kept", record


def _set_color(material: str, color) -> None:
    bpy.data.materials[material].node_tree.nodes["Principled BSDF"].inputs["Base Color"].default_value = (*color, 1)


def _move_vertex(name: str) -> None:
    mesh = bpy.data.objects[name].data
    mesh.vertices[0].co.z += 0.3
    mesh.update()


def check_errors_are_reported() -> None:
    """No camera: the render stops with Blender's error report naming the problem (a RuntimeError
    for a script), and Blender renders again once it is fixed. Nothing to render is no error: the
    world alone is rendered (checks_scene_features), with the reason as a warning."""
    scene = harness.boxes_scene()
    use_engine(scene, backend="cpu")
    camera = scene.camera
    scene.camera = None
    _expect_render_error("camera")
    scene.camera = camera
    for obj in list(scene.objects):
        if obj.type == "MESH":
            obj.hide_render = obj.hide_viewport = True
            obj.hide_set(True)
    assert bpy.ops.render.render() == {"FINISHED"}
    for obj in scene.objects:
        obj.hide_render = obj.hide_viewport = False
        obj.hide_set(False)
    assert bpy.ops.render.render() == {"FINISHED"}


def _expect_render_error(fragment: str) -> None:
    try:
        bpy.ops.render.render()
    except RuntimeError as error:
        assert fragment in str(error), f"'{fragment}' not in '{error}'"
        return
    raise AssertionError(f"the render did not fail with '{fragment}'")
