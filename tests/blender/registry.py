"""Every Blender check of bvhlab, listed once: tests/blender/run.py runs them in order (under a
Blender binary or Python with bpy as a module), and pytest makes one test of each
(tests/python/test_blender_checks.py, ids "group/name").

A group's check modules are imported only when the group is listed (`checks`): under a Blender
binary bvhlab is importable only once the install group has installed the zip.
"""

from __future__ import annotations

import json
import os
import sys
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path

SCENES_JSON = Path(__file__).resolve().parents[2] / "blender_scenes" / "scenes.json"

#: In run order.
GROUPS = ("install", "export", "addon", "instancing", "engine", "cameras", "no_vulkan", "gpu")
#: Groups pytest runs in a child process (tests/blender/run.py --only ...), never in its own:
#: install (enables the zip's add-on in place of the one from addon/), instancing (before issue
#: 39's fix these segfaulted or hung Blender in most runs), no_vulkan (VK_DRIVER_FILES must be set
#: before the process's first Vulkan instance), gpu (Blender aborts the process when its GPU
#: start-up fails).
CHILD_GROUPS = frozenset({"install", "instancing", "no_vulkan", "gpu"})
#: Groups that need the add-on enabled (from addon/ unless the install group installed the zip).
ADDON_GROUPS = frozenset(GROUPS) - {"install", "export"}


@dataclass(frozen=True)
class Check:
    group: str
    name: str
    function: Callable
    args: tuple = ()
    folder: bool = False  # takes an empty folder of its own as its first argument
    zip: bool = False  # takes the extension zip as its first argument
    binary: bool = False  # only under a Blender binary (it runs `blender` on the command line, presses Esc)
    python: tuple[int, int] = (3, 0)  # the oldest Python it means anything under

    @property
    def id(self) -> str:
        return f"{self.group}/{self.name}"

    @property
    def child(self) -> bool:
        return self.group in CHILD_GROUPS

    def skip_reason(self, binary: bool) -> str | None:
        if self.binary and not binary:
            return "needs a Blender binary (tests/blender/run.py under blender)"
        if sys.version_info < self.python:
            return f"needs Python {'.'.join(map(str, self.python))} or later"
        return None

    def run(self, folder: Path | None = None, zip_path: Path | None = None) -> None:
        first = (zip_path,) if self.zip else (folder,) if self.folder else ()
        if self.folder:
            folder.mkdir(parents=True, exist_ok=True)
        self.function(*first, *self.args)


def _install() -> Iterator[Check]:
    import checks_install
    import checks_versions

    # Where a stable-ABI wheel could load.
    yield Check(
        "install",
        "abi3_beside_cp311_refused",
        checks_versions.check_abi3_beside_cp311_refused,
        zip=True,
        python=(3, 12),
    )
    yield Check("install", "install_enable_disable", checks_install.check_install_enable_disable, zip=True)
    yield Check("install", "installed_core_is_this_pythons", checks_versions.check_installed_core_is_this_pythons)
    yield Check(
        "install",
        "installed_over_while_running",
        checks_install.check_installed_over_while_running,
        zip=True,
        binary=True,
    )


def _export() -> Iterator[Check]:
    import checks_bundled
    import checks_cases as cases
    import checks_live
    import checks_shown_object as shown

    for name in json.loads(SCENES_JSON.read_text()):
        yield Check("export", f"bundled_{name}", checks_bundled.check_bundled_scene, args=(name,))
    for check in (
        cases.check_scope_selected_and_visible,
        cases.check_collection_instances,
        cases.check_material_slots_per_triangle,
        cases.check_analytic_sphere_radius,
        cases.check_camera_sensor_fits,
        cases.check_bad_input_errors,
        cases.check_loose_vertices_far_or_not_a_number_are_not_refused,
        cases.check_a_bad_light_material_or_world_is_named,
        cases.check_a_sheared_camera_is_warned_of,
        cases.check_missing_camera_and_light_substituted,
        cases.check_linked_duplicates_of_a_mesh_in_edit_mode,
        cases.check_a_scene_or_view_layer_not_yet_evaluated,
    ):
        yield Check("export", check.__name__.removeprefix("check_"), check)
    yield Check("export", "scene_file_round_trip", cases.check_scene_file_round_trip, folder=True)
    yield Check("export", "large_export", checks_bundled.check_large_export)
    yield Check(
        "export", "moves_are_placed_as_the_walk_places_them", checks_live.check_moves_are_placed_as_the_walk_places_them
    )
    for check in (shown.check_instances_are_read_as_blender_shows_them, shown.check_walks_of_instances_leak_nothing):
        yield Check("export", check.__name__.removeprefix("check_"), check)


def _addon() -> Iterator[Check]:
    import checks_addon as addon
    import checks_settings_path as settings_path

    for name, variants in addon.BUILD_SCENES.items():
        yield Check("addon", f"build_matches_direct_{name}", addon.check_build_matches_direct, args=(name, variants))
    for check in (
        addon.check_overlay_ranges,
        addon.check_build_shows_overlay,
        addon.check_bad_input_reports,
        addon.check_render,
        addon.check_render_without_light,
        addon.check_the_sphere_switch_set_from_a_script_is_synced,
    ):
        yield Check("addon", check.__name__.removeprefix("check_"), check)
    yield Check("addon", "export_stats", addon.check_export_stats, folder=True)
    yield Check("addon", "compare", addon.check_compare, folder=True)
    yield Check("addon", "defaults_are_the_cores", settings_path.check_defaults_are_the_cores)
    yield Check("addon", "render_paths_agree", settings_path.check_render_paths_agree, folder=True)
    yield Check(
        "addon",
        "one_tree_for_build_f12_render_export",
        settings_path.check_one_tree_for_build_f12_render_export,
        folder=True,
    )
    yield Check(
        "addon",
        "renders_and_the_viewport_leave_the_sidebar_a_tree_and_its_scene",
        settings_path.check_renders_and_the_viewport_leave_the_sidebar_a_tree_and_its_scene,
        folder=True,
    )
    yield Check("addon", "path_properties", addon.check_path_properties, folder=True)
    yield Check("addon", "engine_panels", addon.check_engine_panels_follow_the_renders, folder=True)


def _instancing() -> Iterator[Check]:
    import checks_instancing as instancing

    yield Check("instancing", "geometry_nodes_instances", instancing.check_geometry_nodes_instances, folder=True)
    yield Check("instancing", "nested_collection_instances", instancing.check_nested_collection_instances, folder=True)


def _engine() -> Iterator[Check]:
    import checks_engine as engine
    import checks_engine_frames as frames
    import checks_engine_viewport as viewport
    import checks_final as final
    import checks_scene_features as features

    yield Check("engine", "engine_selectable", engine.check_engine_selectable)
    for check in (
        engine.check_combined_and_heatmap_match_the_tracer,
        engine.check_wide_traversal_renders_the_stack_image,
        engine.check_auto_traversal_renders_wide_on_the_cpu_and_stack_for_the_heatmap_pass,
        engine.check_final_render_shows_what_renders_not_what_the_viewport_shows,
        engine.check_an_object_in_edit_mode_is_rendered_with_its_edits,
        engine.check_final_render_takes_blenders_render_threads,
        engine.check_film_transparent_gives_the_share_of_camera_rays_as_alpha,
        engine.check_heatmap_is_box_tests,
        engine.check_depth_is_camera_z,
        engine.check_rerender_reads_only_what_changed,
        frames.check_animation_frames,
        frames.check_animation_light_is_steady,
        frames.check_keyframed_visibility_follows_the_frames,
        frames.check_a_fixed_light_distance_lights_every_chunk_alike,
        engine.check_counter_passes_are_the_cpu_counters,
        features.check_animated_world_colour_follows_the_frames,
        features.check_a_frame_with_nothing_to_render_is_the_world,
        features.check_a_hidden_particle_emitter_is_not_rendered,
        features.check_material_override_stands_in_every_slot,
    ):
        yield Check("engine", check.__name__.removeprefix("check_"), check, folder=True)
    yield Check("engine", "errors_are_reported", engine.check_errors_are_reported)
    yield Check("engine", "depth_of_field_focuses_on_a_bone", features.check_depth_of_field_focuses_on_a_bone)
    yield Check(
        "engine",
        "curves_text_surfaces_and_metaballs_are_exported_once",
        features.check_curves_text_surfaces_and_metaballs_are_exported_once,
    )
    yield Check(
        "engine", "principled_metal_lies_over_transmission", features.check_principled_metal_lies_over_transmission
    )
    yield Check(
        "engine",
        "a_mirrored_camera_mirrors_the_exported_view",
        features.check_a_mirrored_camera_mirrors_the_exported_view,
    )
    for check in (
        viewport.check_view_frustum,
        viewport.check_view_frustum_clip_range,
        viewport.check_orthographic_view_fitted_to_the_scene,
        viewport.check_viewport_worker_levels,
        viewport.check_viewport_build_cancels,
        viewport.check_viewport_settings_update,
        viewport.check_viewport_film_transparent,
        viewport.check_viewport_counter_display,
    ):
        yield Check("engine", check.__name__.removeprefix("check_"), check)
    yield Check("engine", "command_line_frames", frames.check_command_line_frames, folder=True, binary=True)
    yield Check("engine", "exits_without_leaks", final.check_exits_without_leaks, binary=True)
    yield Check("engine", "quits_while_a_thread_renders", final.check_quits_while_a_thread_renders, binary=True)


def _cameras() -> Iterator[Check]:
    import checks_camera_sources as sources
    import checks_cameras as cameras
    import checks_final as final
    import checks_holdout as holdout
    import checks_node_outputs as node_outputs
    import checks_stereo as stereo
    import checks_visibility as visibility

    for name in cameras.SETTINGS:
        yield Check(
            "cameras", f"{name}_against_cycles", cameras.check_setting_against_cycles, args=(name,), folder=True
        )
    for mode in stereo.MODES:
        yield Check(
            "cameras",
            f"stereo_{mode.lower()}_against_cycles",
            stereo.check_stereo_eyes_against_cycles,
            args=(mode,),
            folder=True,
        )
    yield Check(
        "cameras", "multiview_cameras_against_cycles", stereo.check_multiview_cameras_against_cycles, folder=True
    )
    yield Check("cameras", "holdouts_against_cycles", holdout.check_holdouts_against_cycles, folder=True)
    yield Check("cameras", "ray_visibility_against_cycles", visibility.check_ray_visibility_against_cycles, folder=True)
    yield Check(
        "cameras",
        "node_curves_and_points_beside_a_mesh",
        node_outputs.check_node_curves_and_points_beside_a_mesh,
        folder=True,
    )
    for check in (
        final.check_depth_of_field_against_cycles,
        final.check_unrendered_settings_are_said,
        final.check_geometry_and_effects_not_rendered_are_said,
        final.check_odd_borders_are_sized_as_blender_sizes_them,
    ):
        yield Check("cameras", check.__name__.removeprefix("check_"), check, folder=True)
    for check in (
        sources.check_a_strips_camera_override_is_rendered_through,
        sources.check_another_scenes_compositor_frames_at_its_size,
        sources.check_each_views_camera_decides_whether_it_draws_the_overlay,
    ):
        yield Check("cameras", check.__name__.removeprefix("check_"), check, folder=True)
    yield Check(
        "cameras",
        "a_panorama_views_camera_drops_the_overlay_and_renders",
        sources.check_a_panorama_views_camera_drops_the_overlay_and_renders,
    )
    yield Check("cameras", "viewport_says_what_it_does_not_show", final.check_viewport_says_what_it_does_not_show)
    yield Check("cameras", "huge_f12_is_refused_before_allocating", final.check_huge_f12_is_refused_before_allocating)
    yield Check(
        "cameras", "esc_keeps_the_samples_done", final.check_esc_keeps_the_samples_done, folder=True, binary=True
    )


def _without_vulkan_driver(check: Callable) -> Callable:
    def run() -> None:
        # Read when the process makes its first Vulkan instance, which no earlier check does (they
        # use the CPU); Blender's own GPU back-end (OpenGL) does not read it.
        os.environ["VK_DRIVER_FILES"] = os.environ["VK_ICD_FILENAMES"] = "/nonexistent/bvhlab_icd.json"
        check()

    return run


def _no_vulkan() -> Iterator[Check]:
    import checks_addon

    yield Check("no_vulkan", "no_vulkan_reported", _without_vulkan_driver(checks_addon.check_no_vulkan_reported))


def _gpu() -> Iterator[Check]:
    import checks_gpu as gpu

    for check in (
        gpu.check_overlay_pixels,
        gpu.check_overlay_colour_by_depth,
        gpu.check_overlay_colour_by_measure,
        gpu.check_overlay_million_boxes,
        gpu.check_overlay_two_level_boxes,
    ):
        yield Check("gpu", check.__name__.removeprefix("check_"), check)


_LISTS = {
    "install": _install,
    "export": _export,
    "addon": _addon,
    "instancing": _instancing,
    "engine": _engine,
    "cameras": _cameras,
    "no_vulkan": _no_vulkan,
    "gpu": _gpu,
}
assert tuple(_LISTS) == GROUPS


def checks(groups=GROUPS) -> Iterator[Check]:
    """The checks of `groups` in run order, each group's modules imported when it is reached."""
    for group in GROUPS:
        if group in groups:
            yield from _LISTS[group]()
