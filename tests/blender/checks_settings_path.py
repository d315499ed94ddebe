"""One settings path (issue 33) and one tree cache (issue 38), checked where users meet them:
- every default and limit of a render or a build the add-on, the CLI and the Python API offer is
  the core's (RenderOptions / BuildConfig, from the C++ RenderSettings / BuildConfig);
- the sidebar's Render, F12 and Compare hand the core the same render options and build
  settings for the same scene settings (each call into the renderer is recorded);
- Build in the sidebar, then F12, the sidebar's Render and Export stats: one build in all (the
  add-on's tree cache counts them). The add-on must be enabled."""

from __future__ import annotations

import argparse
import inspect
from importlib import import_module

import bpy
import checks_engine
import harness
import numpy as np

import bvhlab
from bvhlab.build_config import BuildConfig
from bvhlab.render_options import (
    AUTO_TRAVERSAL,
    DEFAULT_HEIGHT,
    DEFAULT_WIDTH,
    MAX_LINE_WIDTH,
    RenderOptions,
    options_from,
)

#: Non-default settings for the paths to agree on (every render setting the panel has, and a build).
SETTINGS = {
    "render_supersampling": 2,
    "render_bounces": 3,
    "traversal": "stackless",
    "render_mode": "heatmap",
    "render_overlay": True,
    "overlay_depth_min": 1,
    "overlay_depth_max": 2,
    "overlay_color_by_depth": False,
    "overlay_color": (0.2, 0.9, 0.4, 1.0),
    "overlay_line_width": 2.0,
    "method": "sah",
    "bins": 12,
    "bin_bounds": "centroids",
    "axis": "largest",
    "max_leaf_size": 2,
    "sah_block": "1",
    "backend": "cpu",
}


def _rna(name: str):
    return bpy.types.Scene.bl_rna.properties["bvhlab"].fixed_type.properties[name]


def check_defaults_are_the_cores() -> None:
    """Each consumer's default equals the core's, for every field (a default written a second
    time anywhere fails here)."""
    render, build = RenderOptions(), BuildConfig()
    core = bvhlab._core.RenderSettings()
    assert (render.samples_per_axis, render.max_depth, render.line_width) == (
        core.samples_per_axis,
        core.max_ray_depth,
        core.line_width,
    )
    np.testing.assert_allclose(render.line_color, core.overlay_color)
    # the add-on's settings
    assert _rna("render_supersampling").default == render.samples_per_axis
    assert _rna("render_bounces").default == render.max_depth
    # the add-on and the render CLI ask for the image by the device's fastest walk; the library's
    # default is the report's walk (RenderOptions, the C++ RenderSettings)
    assert render.traversal == bvhlab._core.DEFAULT_TRAVERSAL and _rna("traversal").default == AUTO_TRAVERSAL
    assert _rna("render_mode").default == render.mode
    assert _rna("overlay_color_by_depth").default == render.color_by_depth
    np.testing.assert_allclose(tuple(_rna("overlay_color").default_array)[:3], render.line_color, atol=1e-6)
    assert _rna("overlay_line_width").default == render.line_width
    assert _rna("overlay_line_width").hard_max == MAX_LINE_WIDTH
    assert _rna("render_bounces").hard_max == bvhlab._core.MAX_RAY_DEPTH
    assert _rna("render_supersampling").hard_max == bvhlab._core.MAX_SAMPLES_PER_AXIS
    for name in ("method", "bins", "bin_bounds", "axis", "max_leaf_size"):
        assert _rna(name).default == getattr(build, name), name
    assert int(_rna("sah_block").default) == build.sah_block
    assert (_rna("bins").hard_min, _rna("bins").hard_max) == (bvhlab._core.MIN_BINS, bvhlab._core.MAX_BINS)
    assert _rna("max_leaf_size").hard_max == bvhlab._core.MAX_LEAF_SIZE
    # the Python API and the CLI
    for function in (bvhlab.render, bvhlab.Renderer.start, bvhlab.Renderer.render):
        parameters = inspect.signature(function).parameters
        assert parameters["width"].default == DEFAULT_WIDTH == core.width, function
        assert parameters["height"].default == DEFAULT_HEIGHT == core.height, function
    from bvhlab.cli import parser as cli_parser

    commands = next(a for a in cli_parser()._actions if isinstance(a, argparse._SubParsersAction))
    render_cli = commands.choices["render"]
    args = render_cli.parse_args(["atrium", "--out", "x.png"])
    assert (args.width, args.height) == (DEFAULT_WIDTH, DEFAULT_HEIGHT)
    assert (args.samples_per_axis, args.max_depth, args.traversal) == (
        render.samples_per_axis,
        render.max_depth,
        AUTO_TRAVERSAL,
    )
    from bvhlab.cli.options import build_kwargs

    assert BuildConfig(**build_kwargs(args)) == build, build_kwargs(args)


class _Recorder:
    """Wraps bvhlab.Renderer.start: records the options and tree settings of every render."""

    def __init__(self):
        self.calls: list[tuple[RenderOptions, BuildConfig]] = []
        self._original = bvhlab.Renderer.start

    def __enter__(self):
        original, calls = self._original, self.calls

        def start(renderer, scene, bvh, *args, options=None, **kwargs):
            changes = {k: v for k, v in kwargs.items() if k not in ("camera", "threads", "keep_cost")}
            calls.append((options_from(options, changes), bvh.config))
            return original(renderer, scene, bvh, *args, options=options, **kwargs)

        bvhlab.Renderer.start = start
        return self

    def __exit__(self, *exc):
        bvhlab.Renderer.start = self._original


def check_render_paths_agree(tmp_dir) -> None:
    """The sidebar's Render, F12 and Compare pass the core the same RenderOptions and, but for
    Compare's methods, the same BuildConfig, for the same scene settings."""
    scene = harness.boxes_scene()
    settings = scene.bvhlab
    for name, value in SETTINGS.items():
        setattr(settings, name, value)
    settings.compare_frames, settings.compare_filepath = 1, str(tmp_dir / "compare.csv")
    checks_engine.use_engine(scene)
    expected = settings.render_options()
    assert expected.mode == "heatmap" and expected.line_color == (
        float(np.float32(0.2)),
        float(np.float32(0.9)),
        float(np.float32(0.4)),
    ), expected
    with _Recorder() as sidebar:
        assert bpy.ops.bvhlab.render() == {"FINISHED"}
    with _Recorder() as f12:
        assert bpy.ops.render.render() == {"FINISHED"}
    with _Recorder() as compare:
        assert bpy.ops.bvhlab.compare() == {"FINISHED"}
    assert len(sidebar.calls) == 1 and len(f12.calls) == 1 and len(compare.calls) >= 7
    config = settings.build_config()
    assert sidebar.calls[0] == (expected, config), sidebar.calls
    assert f12.calls[0] == (expected, config), f12.calls
    for options, built in compare.calls:
        assert options == expected, options
        assert built.replace(method=config.method, bins=config.bins) == config, built  # a row: method, bins


def check_one_tree_for_build_f12_render_export(tmp_dir) -> None:
    """Build in the sidebar, then F12, the sidebar's Render and Export stats: one build (F12 says
    its tree was kept), and all of them use the tree Build made."""
    trees = import_module(harness.addon().__name__ + ".trees")
    scene = harness.boxes_scene()
    checks_engine.use_engine(scene, backend="cpu", render_overlay=False)
    builds = trees.counts.snapshot()[0]
    assert bpy.ops.bvhlab.build() == {"FINISHED"}
    assert trees.counts.snapshot()[0] == builds + 1
    built = harness.addon().state.tree_for(scene).bvh
    with _Recorder() as rendered:
        assert bpy.ops.render.render() == {"FINISHED"}
        assert bpy.ops.bvhlab.render() == {"FINISHED"}
    assert bpy.ops.bvhlab.export_stats(filepath=str(tmp_dir / "stats.json")) == {"FINISHED"}
    assert trees.counts.snapshot()[0] == builds + 1, "F12, Render or Export stats built the tree again"
    assert checks_engine._last_final(scene)["tree"] == "kept"
    assert harness.addon().state.tree_for(scene).bvh is built
    assert len(rendered.calls) == 2
    # another build setting is another tree: built once, then kept
    scene.bvhlab.method = "median"
    assert bpy.ops.render.render() == {"FINISHED"}
    assert bpy.ops.render.render() == {"FINISHED"}
    assert trees.counts.snapshot()[0] == builds + 2, (trees.counts.snapshot(), builds)


def check_renders_and_the_viewport_leave_the_sidebar_a_tree_and_its_scene(tmp_dir) -> None:
    """The one cache shares its trees between the sidebar, F12 and the Rendered viewport, but what a
    render shows is not what the sidebar's tree is of (a probe found each of these):
    - F12 with any engine ran the sidebar's follow on the render's depsgraph and made the tree the
      render's (an object disabled in renders gone) while the panel said nothing was behind:
      Export stats then wrote 24 triangles for a scene of 36. A render's depsgraph is not
      followed now: after Cycles' F12 the tree is the one Build made.
    - F12 with bvhlab's engine updates the shared tree to what renders show: the panel says so
      (behind: RENDERED), and Export stats brings it back to the viewport's 36.
    - the Rendered viewport's update of the shared tree (an object hidden by the eye) left the
      sidebar pairing the new tree with Build's scene, which Pick Box's rule for surfaces hidden
      from camera rays reads beside it ("the geometry does not match the tree"): the scene is
      now the tree's own."""
    import json

    from bvhlab.blender import LiveScene

    addon = harness.addon()
    state, trees = addon.state, import_module(addon.__name__ + ".trees")
    follow, viewport = import_module(addon.__name__ + ".follow"), import_module(addon.__name__ + ".engine.viewport")
    scene = harness.boxes_scene()
    scene.render.resolution_x, scene.render.resolution_y = 16, 12
    bpy.data.objects["Box A"].hide_render = True  # in the viewport, not in renders
    bpy.data.objects["Box C"].visible_camera = False  # so a pick in a traced view reads the scene
    bpy.context.view_layer.update()

    def stats_triangles(name: str) -> int:
        path = tmp_dir / f"{name}.json"
        assert bpy.ops.bvhlab.export_stats(filepath=str(path)) == {"FINISHED"}
        return json.loads(path.read_text())["stats"]["triangles"]

    def paired(built) -> bool:
        return len(built.scene.triangles) + len(built.scene.spheres) == built.bvh.stats["primitives"]

    assert bpy.ops.bvhlab.build() == {"FINISHED"}
    built = state.tree_for(scene)
    made = built.bvh
    assert made.stats["triangles"] == 36 and stats_triangles("built") == 36
    scene.render.engine = "CYCLES"
    scene.cycles.samples = 1
    scene.cycles.use_denoising = False  # Debian's Blender 4.3 has no OpenImageDenoise
    assert bpy.ops.render.render() == {"FINISHED"}
    built = state.tree_for(scene)
    assert built.bvh is made and built.behind == "", built.behind  # the render's depsgraph not followed
    assert stats_triangles("after_cycles") == 36

    checks_engine.use_engine(scene, backend="cpu", render_overlay=False)
    assert bpy.ops.render.render() == {"FINISHED"}
    assert follow.wait()  # a catch-up given to the follow's worker
    built = state.tree_for(scene)
    assert checks_engine._last_final(scene)["tree"] != "kept"  # the render made the tree its own
    # said, or already caught up (the update Blender sends after a render, the boxes being shown)
    caught_up = (built.bvh.stats["triangles"], built.behind) == (36, "")
    assert caught_up or (built.bvh.stats["triangles"], built.behind) == (24, state.RENDERED), (
        built.bvh.stats["triangles"],
        built.behind,
    )
    assert paired(built)
    assert stats_triangles("after_f12") == 36 and state.tree_for(scene).behind == ""

    # the Rendered viewport, fed as view_update feeds it, over the scene with Box B hidden by the eye
    bpy.data.objects["Box B"].hide_set(True)
    bpy.context.view_layer.update()
    live = LiveScene("visible", require_camera=False)
    report = live.sync(bpy.context.evaluated_depsgraph_get(), scene, bpy.context.view_layer)
    key = trees.key_of(scene, scope="visible")
    assert key == state.tree_for(scene).key  # the sidebar's tree is the one the viewport traces
    session = viewport.ViewportSession()
    try:
        session.set_scene(live.scene, report)
        tree = trees.cache.tree(key)
        tree.update(live.scene, report.refittable)  # what the worker does before it traces
    finally:
        session.close()
    built = state.tree_for(scene)
    assert built.bvh.stats["triangles"] == 24 and paired(built)
    assert built.scene is live.scene
