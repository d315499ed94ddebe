import os
from pathlib import Path

import numpy as np
import pytest

# Mesa's shader cache inside the build tree, never in ~/.cache (lavapipe compiles on first use).
_cache = Path(__file__).resolve().parents[2] / "build" / "mesa-cache"
os.environ.setdefault("MESA_SHADER_CACHE_DIR", str(_cache))
os.environ.setdefault("XDG_CACHE_HOME", str(_cache))

from bvhlab.library import procedural


@pytest.fixture(scope="session")
def small_scene():
    """A few hundred triangles and spheres, clustered and scattered."""
    rng = np.random.default_rng(3)
    tris = procedural.random_triangles(400, size=0.15, seed=1)
    tris[:200] = tris[:200] * 0.3 + 0.1  # a dense cluster
    spheres = procedural.random_spheres(60, radius=0.04, seed=2)
    spheres[:, :3] += rng.normal(0, 0.01, (60, 3)).astype(np.float32)
    return np.ascontiguousarray(tris), np.ascontiguousarray(spheres)


@pytest.fixture(scope="session")
def knot_mesh():
    """A real mesh of 60k triangles (bumpy torus knot)."""
    return procedural.torus_knot(60000)


# -- selection (pyproject's markers): `make check` runs -m "not slow and not full_zip" -----------
#: Modules that use a Vulkan device, and modules that import bpy or run Blender in a child.
VULKAN_MODULES = {
    "test_bench_render", "test_cli", "test_cli_compare", "test_counters", "test_export_instances", "test_holdout",
    "test_instance_precision", "test_render_api", "test_render_bounded", "test_render_cameras", "test_render_cpu",
    "test_render_precision", "test_render_reentry", "test_render_robust", "test_render_vulkan", "test_ray_visibility",
}  # fmt: skip
BPY_MODULES = {
    "test_addon", "test_addon_install", "test_addon_writes", "test_blender_checks", "test_blender_errors",
    "test_docs_pictures", "test_addon_pick", "test_export_instances", "test_animate_blend", "test_addon_counters",
    "test_addon_pick_two_level", "test_live_sync",
}  # fmt: skip
#: test_blender_checks.py's tests (tests/blender/registry.py) of these groups use a Vulkan device.
VULKAN_GROUPS = {"addon", "engine", "cameras", "no_vulkan", "gpu"}
#: Tests over about 2 s in a full run here (pytest --durations; 2026-12-02, 2 cores: 125 s in all,
#: these 12 took 49 s). Matched as the start of the test's node id within its module.
SLOW = (
    "test_cli_compare.py::test_compare_writes_table_charts_figures_and_sheets",
    "test_cli_compare.py::test_compare_measures_the_overlay_claim",
    "test_blender_checks.py::test_check[instancing/",  # one child runs the group: its first test takes the time
    "test_render_robust.py::test_ctrl_c_stops_a_long_render",
    "test_docs_code.py::test_the_documented_code_runs[docs/api.md]",  # an 800×600 CPU render and node data
    "test_scene.py::test_load_checks_sizes_before_reading_data",
    "test_concurrency.py::test_threads_share_the_core_and_get_serial_results",
    "test_shared_tree.py::test_refit_while_other_threads_read",
    "test_blender_checks.py::test_check[gpu/",
    "test_interrupt.py::test_ctrl_c_stops_the_work_promptly[build]",
    "test_render_bounded.py::test_ten_thousand_copies_of_one_triangle",
    "test_render_bounded.py::test_bundled_scene_at_16x16_samples",
    "test_render_vulkan.py::test_scene_larger_than_one_storage_buffer_binding",
    "test_animate_blend.py::",  # bpy plays the two animated .blend files in children: 90 s for the module
)


@pytest.hookimpl(tryfirst=True)  # before -m deselects: `items` is everything collected
def pytest_collection_modifyitems(config, items):
    ids = [f"{item.path.name}::{item.name}" for item in items]
    for item, node in zip(items, ids):
        module = item.path.stem
        check = item.callspec.params.get("check") if module == "test_blender_checks" else None
        if module in VULKAN_MODULES or (check is not None and check.group in VULKAN_GROUPS):
            item.add_marker(pytest.mark.vulkan)
        if module in BPY_MODULES:
            item.add_marker(pytest.mark.bpy)
        if node.startswith(SLOW):
            item.add_marker(pytest.mark.slow)
    if len(items) > 400:  # the whole suite: a name in SLOW that names no test is stale
        stale = [name for name in SLOW if not any(node.startswith(name) for node in ids)]
        if stale:
            raise pytest.UsageError(f"conftest.SLOW names no test: {stale}")
