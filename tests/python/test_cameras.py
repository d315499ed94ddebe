"""Issue 33's acceptance under bpy 4.2: every camera kind and setting of the render engine against
Cycles' Depth pass, on the CPU reference and Vulkan, F12 and the viewport's camera; depth of field
against Cycles; unrendered settings said; a huge F12 refused before Blender allocates it (the same
checks run under bpy 5.2 and a real Blender binary through tests/blender/run.py, group cameras,
which also presses Esc during an F12)."""

import blender_checks  # noqa: F401
import checks_cameras  # noqa: E402
import checks_final  # noqa: E402
import harness
import pytest


@pytest.fixture(scope="module", autouse=True)
def addon_enabled():
    harness.enable_addon_from_source()


@pytest.fixture(scope="module")
def backends():
    return checks_cameras.vulkan_backends()


@pytest.mark.parametrize("name", checks_cameras.SETTINGS)
def test_depth_pass_equals_cycles(tmp_path, backends, name):
    checks_cameras.check_settings_against_cycles(tmp_path, backends, names=[name])


def test_depth_of_field_blurs_as_cycles_does(tmp_path):
    checks_final.check_depth_of_field_against_cycles(tmp_path)


def test_unrendered_settings_are_said(tmp_path):
    checks_final.check_unrendered_settings_are_said(tmp_path)


def test_odd_borders_are_sized_as_blender_sizes_them(tmp_path):
    checks_final.check_odd_borders_are_sized_as_blender_sizes_them(tmp_path)


def test_viewport_says_what_it_does_not_show():
    checks_final.check_viewport_says_what_it_does_not_show()


def test_huge_f12_is_refused_before_blender_allocates_it():
    checks_final.check_huge_f12_is_refused_before_allocating()
