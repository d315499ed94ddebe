"""bvhlab.blender: Blender scene → bvhlab.Scene, on the bundled scenes and on small scenes made
here (bpy imported as a module; the checks live in tests/blender, shared with run.py)."""

import blender_checks  # noqa: F401  (import path for the shared checks)
import checks_bundled  # noqa: E402
import checks_cases  # noqa: E402
import harness  # before bpy
import pytest


@pytest.mark.parametrize("name", list(harness.scenes_index()))
def test_bundled_scene_exports_as_scenes_json_says(name):
    checks_bundled.check_bundled_scene(name)


@pytest.mark.parametrize("check", checks_cases.CASE_CHECKS, ids=lambda c: c.__name__.removeprefix("check_"))
def test_export_case(check):
    check()


def test_a_million_triangles_export():
    checks_bundled.check_large_export()


def test_scene_file_round_trip(tmp_path):
    checks_cases.check_scene_file_round_trip(tmp_path)
