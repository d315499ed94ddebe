"""The render engine "bvhlab Whitted" under bpy 4.2, the add-on enabled in place from addon/ (the
same checks run under bpy 5.2 and a real Blender binary through tests/blender/run.py, which
also renders `blender -b ... -a` on the command line)."""

import blender_checks  # noqa: F401
import checks_engine  # noqa: E402
import checks_engine_viewport  # noqa: E402
import harness
import pytest


@pytest.fixture(scope="module", autouse=True)
def addon_enabled():
    harness.enable_addon_from_source()


def test_engine_is_selectable_with_blenders_panels():
    checks_engine.check_engine_selectable()


def test_combined_and_heatmap_passes_equal_the_cpu_reference(tmp_path):
    checks_engine.check_combined_and_heatmap_match_the_tracer(tmp_path)


def test_heatmap_pass_is_the_box_tests_of_bvh_intersect(tmp_path):
    checks_engine.check_heatmap_is_box_tests(tmp_path)


def test_depth_pass_is_camera_z_by_brute_force(tmp_path):
    checks_engine.check_depth_is_camera_z(tmp_path)


def test_rerender_reads_only_what_changed(tmp_path):
    checks_engine.check_rerender_reads_only_what_changed(tmp_path)


def test_animation_frames_follow_the_motion(tmp_path):
    checks_engine.check_animation_frames(tmp_path)


def test_render_errors_are_reported():
    checks_engine.check_errors_are_reported()


def test_viewport_frustum_matches_blenders_projection():
    checks_engine_viewport.check_view_frustum()


def test_viewport_worker_preview_full_refined():
    checks_engine_viewport.check_viewport_worker_levels()


def test_viewport_build_cancels_with_esc():
    checks_engine_viewport.check_viewport_build_cancels()


def test_viewport_settings_set_by_a_script_update_the_viewport():
    checks_engine_viewport.check_viewport_settings_update()
