"""The add-on's settings under bpy, enabled in place from addon/ (its operators are checked by the
addon group of tests/blender/registry.py, in test_blender_checks.py; the zip in test_addon_install.py)."""

import blender_checks  # noqa: F401
import harness
import pytest


@pytest.fixture(scope="module", autouse=True)
def addon_enabled():
    harness.enable_addon_from_source()


def test_settings_take_names_defaults_and_limits_from_the_core():
    """One definition: the panel's lists, defaults and limits are the core's, and each name has a
    label and a tooltip."""
    import bpy

    import bvhlab

    property_items = __import__(harness.addon().__name__ + ".property_items", fromlist=["METHOD_ITEMS"])
    assert [item[0] for item in property_items.METHOD_ITEMS] == list(bvhlab.METHODS)
    assert [item[0] for item in property_items.AXIS_ITEMS] == list(bvhlab.AXES)
    assert [item[0] for item in property_items.BIN_BOUNDS_ITEMS] == list(bvhlab.build_config.BIN_BOUNDS)
    labelled = property_items.METHOD_ITEMS + property_items.AXIS_ITEMS + property_items.BIN_BOUNDS_ITEMS
    assert all(label and tooltip for _, label, tooltip in labelled)
    assert property_items.MAX_DEPTH == bvhlab.bvh.MAX_TREE_HEIGHT - 1
    rna = bpy.types.Scene.bl_rna.properties["bvhlab"].fixed_type.properties
    assert (
        rna["method"].default == bvhlab.build_config.DEFAULT_METHOD
        and rna["axis"].default == bvhlab.build_config.DEFAULT_AXIS
    )
    assert rna["bins"].default == bvhlab.build_config.DEFAULT_BINS
    assert rna["bin_bounds"].default == bvhlab.build_config.DEFAULT_BIN_BOUNDS
    assert (rna["bins"].hard_min, rna["bins"].hard_max) == (bvhlab._core.MIN_BINS, bvhlab._core.MAX_BINS)
    assert rna["max_leaf_size"].default == bvhlab.build_config.DEFAULT_MAX_LEAF_SIZE
    blocks = [int(i.identifier) for i in rna["sah_block"].enum_items]
    assert blocks == [1 << k for k in range(bvhlab.build_config.MAX_SAH_BLOCK.bit_length())]
    assert int(rna["sah_block"].default) == bvhlab.build_config.DEFAULT_SAH_BLOCK
    assert rna["render_bounces"].hard_max == bvhlab._core.MAX_RAY_DEPTH
    assert rna["render_supersampling"].hard_max == bvhlab._core.MAX_SAMPLES_PER_AXIS
    assert [i.identifier for i in rna["traversal"].enum_items] == ["auto", *bvhlab._core.TRAVERSALS]
    assert rna["traversal"].default == "auto"  # the device's fastest walk (RenderOptions.for_backend)
    # a .blend stores the number: those saved before Auto came (stack 0, stackless 1, wide 2) load as saved
    assert [i.value for i in rna["traversal"].enum_items] == [3, 0, 1, 2]
    assert [i.identifier for i in rna["backend"].enum_items] == ["auto", "vulkan", "cpu"]
