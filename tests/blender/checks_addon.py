"""Operator checks (the add-on must be enabled: harness.enable_addon_from_source or an installed
zip): Build against bvhlab.build on the same export, overlay box counts, exported stats files,
Render against Blender's own ray casts, Compare, and bad input reported without a crash."""

from __future__ import annotations

import csv
import json
import math
import os
import warnings

import bpy
import harness
import numpy as np

import bvhlab
from bvhlab.blender import export_scene
from bvhlab.build_config import method_from_label as method_kwargs

BUILD_VARIANTS = (
    {"method": "sah", "bins": 12},
    {"method": "sah", "bins": 32, "bin_bounds": "centroids"},
    {"method": "median"},
    {"method": "mean", "max_leaf_size": 4},
    {"method": "sweep_sah", "axis": "best"},
    {"method": "sah", "bins": 8, "max_leaf_size": 8, "sah_block": 1},
    {"method": "sah", "bins": 8, "max_leaf_size": 8, "sah_block": 16},
)
#: Scenes the Build operator is checked on, with the variants (the large one gets the quick two).
BUILD_SCENES = {"five_spheres": BUILD_VARIANTS, "whitted": BUILD_VARIANTS, "suzanne_250k": BUILD_VARIANTS[:2]}


def _configure(**settings):
    for name, value in settings.items():
        # the SAH block is an enum of powers of two (its identifiers are strings)
        setattr(bpy.context.scene.bvhlab, name, str(value) if name == "sah_block" else value)


def _built():
    return harness.addon().state.tree_for(bpy.context.scene)


def _message() -> tuple:
    """The panel's last message for the scene: (level, text)."""
    state = harness.addon().state
    return state.messages[state.key(bpy.context.scene)]


def check_build_matches_direct(name: str, variants=BUILD_VARIANTS) -> None:
    """For each variant: the operator's tree has the stats and the nodes of bvhlab.build on the
    scene exported directly (only the build time may differ)."""
    harness.open_scene(name)
    for variant in variants:
        _configure(
            scope="visible", method="sah", bins=12, bin_bounds="box", axis="largest", max_leaf_size=1, sah_block=4
        )
        _configure(**variant)
        assert bpy.ops.bvhlab.build() == {"FINISHED"}
        built = _built()
        direct = bvhlab.build(
            export_scene(bpy.context, require_camera=False),
            **{"method": "sah", "bins": 12, "bin_bounds": "box", "axis": "largest", "max_leaf_size": 1, "sah_block": 4}
            | variant,
        )
        ours, theirs = built.bvh.stats, direct.stats
        for key in theirs:
            if key != "build_ms":
                assert ours[key] == theirs[key], (name, variant, key, ours[key], theirs[key])
        assert built.bvh.nodes.tobytes() == direct.nodes.tobytes(), (name, variant)


def check_overlay_ranges() -> None:
    """The overlay's table holds, for every depth range, exactly the nodes (or leaves) at those
    depths, with the boxes bvh.boxes gives; the depth settings stay within the tree's height."""
    from importlib import import_module

    batch = import_module(harness.addon().__name__ + ".overlay.batch")
    harness.open_scene("whitted")
    _configure(method="sah", max_leaf_size=1, overlay_depth_min=0, overlay_depth_max=3)
    bpy.ops.bvhlab.build()
    bvh = _built().bvh
    stats = bvh.stats
    height = stats["height"]
    table, leaves = batch.BoxTable(bvh), batch.BoxTable(bvh, leaves_only=True)
    leaf_set = {(tuple(node["lo"]), tuple(node["hi"])) for node in bvh.nodes[bvh.is_leaf]}
    for depth_min, depth_max in ((0, 0), (1, 2), (3, height - 1), (0, height - 1), (height - 1, height - 1)):
        first, count = table.depth_slice(depth_min, depth_max)
        assert count == sum(stats["nodes_per_depth"][depth_min : depth_max + 1])
        lo, hi, depth = bvh.boxes(depth_min, depth_max)
        rows = table.rows[first : first + count]
        assert np.array_equal(rows[:, 0:3], lo) and np.array_equal(rows[:, 4:7], hi)
        assert np.array_equal(rows[:, 3], depth)
        first, leaf_count = leaves.depth_slice(depth_min, depth_max)
        assert leaf_count == sum(stats["leaves_per_depth"][depth_min : depth_max + 1])
        leaf_rows = leaves.rows[first : first + leaf_count]
        assert np.all((leaf_rows[:, 3] >= depth_min) & (leaf_rows[:, 3] <= depth_max))
        assert all((tuple(r[0:3]), tuple(r[4:7])) in leaf_set for r in leaf_rows), "a non-leaf in the leaves"
    assert table.depth_slice(height, height + 3)[1] == 0
    settings = bpy.context.scene.bvhlab
    settings.overlay_depth_max = 60
    assert settings.overlay_depth_max == height - 1
    settings.overlay_depth_min = height + 5
    assert settings.overlay_depth_min == height - 1 and settings.overlay_depth_max == height - 1
    settings.overlay_depth_max = 1
    assert settings.overlay_depth_min == 1


def check_build_shows_overlay() -> None:
    """Pressing Build is asking to see the boxes: the overlay is on afterwards, even when the user
    had never ticked "Viewport Boxes"."""
    harness.boxes_scene()
    settings = bpy.context.scene.bvhlab
    assert not settings.overlay_show, "the overlay must start off (nothing to show before a build)"
    assert bpy.ops.bvhlab.build() == {"FINISHED"}
    assert settings.overlay_show, "Build left the overlay off"


def check_export_stats(tmp_dir) -> None:
    """JSON holds bvh.stats unchanged; the CSV's rows give back every value and list."""
    harness.open_scene("five_spheres")
    _configure(method="mean")
    bpy.ops.bvhlab.build()
    path = tmp_dir / "five_spheres_stats.json"
    assert bpy.ops.bvhlab.export_stats(filepath=str(path)) == {"FINISHED"}
    stats = _built().bvh.stats
    written = json.loads(path.read_text())
    assert written["stats"] == stats and written["about"]["settings"]["method"] == "mean"
    from_csv: dict = {}
    with path.with_suffix(".csv").open() as f:
        for row in csv.DictReader(f):
            if row["index"]:
                from_csv.setdefault(row["metric"], []).append(int(row["value"]))
            else:
                from_csv[row["metric"]] = row["value"]
    for key, value in stats.items():
        if isinstance(value, list):
            assert from_csv[key] == value, key
        elif isinstance(value, (int, float)):
            assert math.isclose(float(from_csv[key]), value), key
        else:  # a null of the JSON (bins of a method that does not bin) is an empty field
            assert from_csv[key] == ("" if value is None else str(value)), key


def blender_hit_mask(scene, camera, width: int, height: int) -> np.ndarray:
    """(height, width) bool, row 0 at the top: does a pinhole ray through each pixel centre hit
    anything, by Blender's own scene.ray_cast (independent of bvhlab's trees and tracer)."""
    position, look_at, up = (np.array(v, np.float64) for v in (camera.position, camera.look_at, camera.up))
    forward = (look_at - position) / np.linalg.norm(look_at - position)
    right = np.cross(forward, up)
    right /= np.linalg.norm(right)
    true_up = np.cross(right, forward)
    tan = math.tan(math.radians(camera.fov_y) / 2)
    depsgraph = bpy.context.evaluated_depsgraph_get()
    mask = np.zeros((height, width), bool)
    for y in range(height):
        for x in range(width):
            px = ((x + 0.5) / width * 2 - 1) * tan * width / height
            py = (1 - (y + 0.5) / height * 2) * tan
            direction = forward + px * right + py * true_up
            mask[y, x] = scene.ray_cast(depsgraph, position.tolist(), direction.tolist())[0]
    return mask


def check_render() -> None:
    """Render on the CPU backend: the Image "BVH Render" has the scene's resolution, and its
    non-sky pixels are where Blender's ray casts hit (boundary pixels aside)."""
    scene = harness.boxes_scene()
    _configure(backend="cpu", render_bounces=2, render_samples=1, render_overlay=False, render_mode="shade")
    assert bpy.ops.bvhlab.render() == {"FINISHED"}
    image = bpy.data.images["BVH Render"]
    width, height = scene.render.resolution_x, scene.render.resolution_y
    assert tuple(image.size) == (width, height)
    pixels = np.empty(width * height * 4, np.float32)
    image.pixels.foreach_get(pixels)
    top_first = pixels.reshape(height, width, 4)[::-1]
    exported = export_scene(bpy.context)
    drawn = np.abs(top_first[..., :3] - np.array(exported.sky)).max(-1) > 0.02
    hits = blender_hit_mask(scene, exported.camera, width, height)
    padded = np.pad(hits, 1, mode="edge")
    neighbours = [padded[1 + dy : 1 + dy + height, 1 + dx : 1 + dx + width] for dy in (-1, 0, 1) for dx in (-1, 0, 1)]
    interior = np.all(neighbours == hits, axis=0)  # pixels away from a silhouette
    assert hits.any() and (~hits).any()
    agreement = (drawn == hits)[interior].mean()
    assert agreement > 0.99, f"only {agreement:.3f} of the interior pixels agree with Blender's ray casts"
    assert harness.addon().state.last_render[harness.addon().state.key(scene)]["backend"] == "cpu"


def check_compare(tmp_dir) -> None:
    """Every split method gets a row with the height of a direct build, written as CSV."""
    harness.boxes_scene()
    path = tmp_dir / "compare.csv"
    _configure(backend="cpu", compare_frames=1, compare_filepath=str(path), axis="largest", max_leaf_size=1)
    assert bpy.ops.bvhlab.compare() == {"FINISHED"}
    with path.open() as f:
        rows = list(csv.DictReader(f))
    methods = {row["method"] for row in rows}
    assert methods == {"median", "mean", "midpoint", "sah12", "sah32", "sweep_sah", "lbvh"}, methods
    exported = export_scene(bpy.context)
    for row in rows:
        direct = bvhlab.build(
            exported, axis="largest", max_leaf_size=1, **method_kwargs(row["method"])
        )  # as configured
        assert int(row["height"]) == direct.stats["height"] and float(row["frame_ms"]) > 0
    assert len(harness.addon().state.comparisons[harness.addon().state.key(bpy.context.scene)]) == len(rows)


def _expect_report(operator, fragment: str) -> None:
    """An ERROR report reaches a script as RuntimeError; the message must say what is wrong."""
    try:
        operator()
    except RuntimeError as error:
        assert fragment in str(error), f"'{fragment}' not in '{error}'"
        return
    raise AssertionError(f"no error report containing '{fragment}'")


def _still_alive() -> None:
    harness.boxes_scene()
    _configure(scope="visible")
    assert bpy.ops.bvhlab.build() == {"FINISHED"}


def check_bad_input_reports() -> None:
    """Empty selection, a NaN vertex, no camera: an ERROR report naming the problem, then Blender
    still runs operators."""
    harness.boxes_scene()
    _configure(scope="selected")
    for obj in bpy.context.scene.objects:
        obj.select_set(False)
    _expect_report(bpy.ops.bvhlab.build, "no mesh in scope")
    _still_alive()
    bpy.data.objects["Box C"].data.vertices[0].co.z = float("nan")
    _expect_report(bpy.ops.bvhlab.build, "Box C")
    _still_alive()
    bpy.context.scene.camera = None
    assert bpy.ops.bvhlab.build() == {"FINISHED"}, "a tree needs no camera"
    _expect_report(bpy.ops.bvhlab.render, "no camera")
    _still_alive()


def check_render_without_light() -> None:
    """No light: the render goes on with bvhlab's default light and says so in a WARNING."""
    harness.boxes_scene()
    bpy.data.objects.remove(bpy.data.objects["Light"])
    _configure(backend="cpu", render_bounces=1)
    assert bpy.ops.bvhlab.render() == {"FINISHED"}
    state = harness.addon().state
    level, text = state.messages[state.key(bpy.context.scene)]
    assert level == "WARNING" and "no visible light" in text, (level, text)
    _still_alive()


def check_no_vulkan_reported() -> None:
    """backend="vulkan" where no Vulkan driver loads (run with VK_DRIVER_FILES pointing nowhere)."""
    harness.boxes_scene()
    _configure(backend="vulkan")
    _expect_report(bpy.ops.bvhlab.render, "No Vulkan")
    _still_alive()


PATH_SUBTYPES = ("FILE_PATH", "DIR_PATH")


def _addon_structs() -> list:
    """(name, bl_rna) of the add-on's PropertyGroups and operators, and of Blender's data types
    (the add-on adds properties to some)."""
    package = harness.addon().__name__
    structs = [
        (c.__name__, c.bl_rna) for c in bpy.types.PropertyGroup.__subclasses__() if c.__module__.startswith(package)
    ]
    structs += [(f"bpy.ops.bvhlab.{n}", getattr(bpy.ops.bvhlab, n).get_rna_type()) for n in dir(bpy.ops.bvhlab)]
    return structs + [(t.__name__, t.bl_rna) for t in bpy.types.ID.__subclasses__()]


def addon_path_properties() -> list:
    """(owner, name, property) of every path property of the add-on."""
    return [
        (owner, prop.identifier, prop)
        for owner, rna in _addon_structs()
        for prop in rna.properties
        if prop.type == "STRING"
        and prop.subtype in PATH_SUBTYPES
        and (owner.startswith(("BVHLAB", "bpy.ops.bvhlab")) or prop.identifier.startswith("bvhlab"))
    ]


def check_path_properties(tmp_dir) -> None:
    """Every path property of the add-on is a path Blender knows as one the add-on writes (an
    output) and, where Blender has the option (4.5 on), one that takes "//" as the .blend's folder:
    Blender 5.2 warns (`does not support blend relative "//" prefix`) and draws the field red
    otherwise. Set to "//..." from a script, Compare's table and Export Stats give no warning and
    their files land beside the saved .blend."""
    found = addon_path_properties()
    names = {f"{owner}.{name}" for owner, name, _ in found}
    assert {"BVHLAB_PG_settings.compare_filepath", "bpy.ops.bvhlab.export_stats.filepath"} <= names, names
    blend_relative = "is_path_supports_blend_relative" in bpy.types.Property.bl_rna.properties
    for owner, name, prop in found:
        assert prop.is_path_output, f"{owner}.{name} is not an output path"
        if blend_relative:
            assert prop.is_path_supports_blend_relative, f"{owner}.{name} does not take a '//' path"
    harness.boxes_scene()
    # unsaved, '//' is Blender's temporary folder, which it deletes when it quits: the report says so
    # (it named the file as if it stayed: probe)
    assert not bpy.data.filepath
    assert bpy.ops.bvhlab.export_stats(filepath="//unsaved_stats.json") == {"FINISHED"}
    said = _message()[1]
    assert "deleted when Blender quits" in said and os.path.isfile(bpy.app.tempdir + "unsaved_stats.json"), said
    bpy.ops.wm.save_as_mainfile(filepath=str(tmp_dir / "paths.blend"))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        _configure(backend="cpu", compare_frames=1, compare_filepath="//paths_compare.csv")
        assert bpy.ops.bvhlab.compare() == {"FINISHED"}
        assert bpy.ops.bvhlab.export_stats(filepath="//paths_stats.json") == {"FINISHED"}
    relative = [str(w.message) for w in caught if "relative" in str(w.message)]
    assert not relative, relative
    assert (tmp_dir / "paths_compare.csv").is_file() and (tmp_dir / "paths_stats.json").is_file()
    assert "deleted when Blender quits" not in _message()[1]
    print(f"path properties: {sorted(names)}")


ENGINE = "BVHLAB_WHITTED"


def _blender_panels() -> list:
    panels, stack = [], list(bpy.types.Panel.__subclasses__())
    while stack:
        panels.append(stack.pop())
        stack.extend(panels[-1].__subclasses__())
    return [p for p in panels if isinstance(getattr(p, "COMPAT_ENGINES", None), set)]


def _render_png(tmp_dir, name: str) -> dict:
    """F12 of the current scene written as PNG: {view suffix: float (h, w, 4)} ("" for one view)."""
    scene = bpy.context.scene
    scene.render.filepath = str(tmp_dir / name)
    assert bpy.ops.render.render(write_still=True) == {"FINISHED"}
    images = {}
    for path in tmp_dir.glob(f"{name}*.png"):
        image = bpy.data.images.load(str(path))
        pixels = np.empty(image.size[0] * image.size[1] * 4, np.float32)
        image.pixels.foreach_get(pixels)
        images[path.stem[len(name) :]] = pixels.reshape(image.size[1], image.size[0], 4)
        bpy.data.images.remove(image)
    return images


def _add_grease_pencil_monkey(location) -> None:
    try:
        bpy.ops.object.gpencil_add(location=location, type="MONKEY")  # Blender 4.2
    except (AttributeError, RuntimeError):
        bpy.ops.object.grease_pencil_add(location=location, type="MONKEY")  # 4.3 on


def check_engine_panels_follow_the_renders(tmp_dir) -> None:
    """Blender's panels show for the engine where its renders follow them. Grease Pencil: Blender
    draws a Grease Pencil object over the engine's image (a render with one in front of the
    camera differs from one without), its panels show. Stereoscopy: the engine renders each view
    (the right eye of a stereo render was empty: its panels were hidden), its panels show.
    Freestyle is drawn too
    (through EEVEE: minutes on llvmpipe, not rendered here), its panels show."""
    shown = {p.__name__ for p in _blender_panels() if ENGINE in p.COMPAT_ENGINES}
    listed = {p.__name__ for p in _blender_panels() if "BLENDER_RENDER" in p.COMPAT_ENGINES}
    scene = harness.boxes_scene()  # 64 × 48
    scene.render.engine = ENGINE
    _configure(backend="cpu", render_bounces=1)
    plain = _render_png(tmp_dir, "plain")[""]
    scene.render.use_multiview, scene.render.views_format = True, "STEREO_3D"
    scene.render.image_settings.views_format = "INDIVIDUAL"
    stereo = _render_png(tmp_dir, "stereo_")
    right_eye = stereo["_R"][..., :3]
    stereo_rendered = right_eye.std() > 0.01 and np.abs(right_eye - stereo["_L"][..., :3]).max() > 0.05
    scene.render.use_multiview = False
    _add_grease_pencil_monkey(location=(0.0, -4.0, 1.0))
    with_pencil = _render_png(tmp_dir, "pencil")[""]
    pencil_drawn = (np.abs(with_pencil - plain)[..., :3].max(-1) > 0.05).mean() > 0.01
    panels = {
        "stereoscopy": ({n for n in listed if "stereo" in n.lower()} | {"RENDER_PT_output_views"}, stereo_rendered),
        "grease pencil": ({n for n in listed if "gpencil" in n.lower() or "grease_pencil" in n.lower()}, pencil_drawn),
        "freestyle": ({n for n in listed if "freestyle" in n.lower()}, True),
    }
    for feature, (names, rendered) in panels.items():
        assert names, f"no {feature} panels found"
        wrong = names - shown if rendered else names & shown
        assert not wrong, (
            f"{feature} is {'' if rendered else 'not '}rendered, yet these show otherwise: {sorted(wrong)}"
        )
    print(f"stereo right eye rendered: {stereo_rendered}; grease pencil drawn: {pencil_drawn}")


def check_the_sphere_switch_set_from_a_script_is_synced() -> None:
    """Object ▸ Analytic sphere set from a script tagged nothing (a get/set property without an
    update function): a sync after it (the Rendered viewport's, the sidebar's) kept the object as
    triangles, and the syncs of moved objects that placed them from Blender's updates alone kept
    it so, while a fresh export had the sphere. Now the switch tags the object's geometry."""
    from bvhlab.blender import LiveScene

    scene = harness.boxes_scene()
    ball = bpy.data.objects["Box A"]
    other = bpy.data.objects["Box B"]
    live = LiveScene("visible", require_camera=False)
    live.sync(bpy.context.evaluated_depsgraph_get(), scene)
    synced = []

    def sync(blender_scene, depsgraph):
        synced.append(live.sync(depsgraph, blender_scene).placed_only)

    bpy.app.handlers.depsgraph_update_post.append(sync)
    try:
        for on in (True, False, True):
            ball.bvhlab_analytic_sphere = on
            bpy.context.view_layer.update()
            other.location.x += 0.25  # then a move placed from its update alone
            bpy.context.view_layer.update()
            synced_scene = live.scene.flattened()
            fresh = export_scene(bpy.context, require_camera=False).flattened()
            assert len(synced_scene.spheres) == len(fresh.spheres) == int(on), (on, len(synced_scene.spheres))
            assert len(synced_scene.triangles) == len(fresh.triangles) == 36 - 12 * on
    finally:
        bpy.app.handlers.depsgraph_update_post.remove(sync)
    assert any(synced), "no sync placed the moved object from its update alone: the case is not met"
