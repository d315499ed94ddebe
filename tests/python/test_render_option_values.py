"""Option values no render or build can use (probe): a NaN or infinite overlay line colour was
taken (nothing checked a colour) and left to whichever backend drew the lines."""

import math

import pytest

import bvhlab


@pytest.mark.parametrize("bad", [math.nan, math.inf, -math.inf])
def test_a_line_color_that_is_not_finite_is_refused(bad):
    with pytest.raises(ValueError, match="line_color must be finite"):
        bvhlab.RenderOptions(overlay_depth=(0, 3), line_color=(1.0, bad, 0.0))
    with pytest.raises(ValueError, match="line_color must be finite"):
        bvhlab.RenderOptions().replace(line_color=(bad, 0, 0))


def test_finite_line_colors_are_taken():
    assert bvhlab.RenderOptions(line_color=(0.0, 0.5, 2.0)).line_color == (0.0, 0.5, 2.0)


def test_settings_beyond_float32_are_refused_with_the_value_given():
    """A build, update or optimize setting of 1e300 arrived in the core's float32 field as inf and
    was refused as "got inf"; it is refused by its own value."""
    import numpy as np

    tris = np.arange(36, dtype=np.float32).reshape(4, 3, 3)
    with pytest.raises(ValueError, match=r"sbvh_alpha must be within float32's range .*got 1e\+300"):
        bvhlab.build(tris, method="sbvh", sbvh_alpha=1e300)
    with pytest.raises(ValueError, match=r"tree_growth must be within float32's range .*got 1e\+39"):
        bvhlab.UpdateConfig(tree_growth=1e39)


@pytest.mark.parametrize("tiny", [1e-46, 1e-40, -1e-46])
def test_settings_float32_holds_only_as_0_or_a_denormal_are_refused(tiny):
    """sbvh_alpha=1e-46 arrived in the core's float32 as 0 (1e-40 as a denormal) and was taken
    silently; batch_fraction and tree_growth were refused as "got 0". Refused by their own value."""
    import numpy as np

    tris = np.arange(36, dtype=np.float32).reshape(4, 3, 3)
    message = rf"must be 0 or of magnitude 1\.175494e-38 to 3\.402823e\+38 .*got {tiny:g}$"
    with pytest.raises(ValueError, match="sbvh_alpha " + message):
        bvhlab.build(tris, method="sbvh", sbvh_alpha=tiny)
    with pytest.raises(ValueError, match="sbvh_alpha " + message):
        bvhlab.BuildConfig(method="sbvh", sbvh_alpha=tiny)
    with pytest.raises(ValueError, match="batch_fraction " + message):
        bvhlab.OptimizeConfig(batch_fraction=tiny)
    # where 0 is refused too, the message does not offer it (an audit), and a setting of at least 1
    # says so first
    if tiny > 0:
        with pytest.raises(ValueError, match="restructure_share " + message.replace("0 or ", "")):
            bvhlab.UpdateConfig(restructure_share=tiny)
    with pytest.raises(ValueError, match=f"tree_growth must be at least 1, got {tiny}$"):
        bvhlab.UpdateConfig(tree_growth=tiny)


def test_zero_and_the_smallest_normal_float32_are_taken():
    import numpy as np

    smallest = float(np.finfo(np.float32).tiny)
    assert bvhlab.BuildConfig(method="sbvh", sbvh_alpha=0.0).sbvh_alpha == 0.0
    assert bvhlab.BuildConfig(method="sbvh", sbvh_alpha=smallest).core().sbvh_alpha == smallest
    assert bvhlab.BuildConfig(method="sbvh", sbvh_alpha=-0.0).sbvh_alpha == 0.0


@pytest.mark.parametrize("name", ["film_transparent", "color_by_depth", "traversal_counters"])
@pytest.mark.parametrize("bad", ["False", 0, 1, 0.5, None])
def test_switches_are_true_or_false_not_truthy(name, bad):
    """film_transparent="False" rendered a transparent film (probe: 289 of 768 pixels with alpha
    0, on both backends): the switches took any value by its truthiness, where the others (Material
    holdout, Camera mirrored) refuse what is not True or False."""
    with pytest.raises(TypeError, match=f"{name} must be True or False, got {bad!r}"):
        bvhlab.RenderOptions(**{name: bad})
    with pytest.raises(TypeError, match=f"{name} must be True or False"):
        bvhlab.RenderOptions().replace(**{name: bad})


def test_a_heatmap_scale_beyond_float32_is_refused_as_given():
    with pytest.raises(ValueError, match=r"heatmap_scale must be within float32's range .*got 1e\+39"):
        bvhlab.RenderOptions(mode="heatmap", heatmap_scale=1e39)


def test_refused_numbers_are_shown_as_given():
    """The core's messages showed a refused float in six decimals: "got -1.000000", and a
    sbvh_alpha of -1e-9 as "got -0.000000", a value that would pass. Each now reads as given."""
    import numpy as np

    tris = np.arange(36, dtype=np.float32).reshape(4, 3, 3)
    cases = [
        (lambda: bvhlab.build(tris, method="sbvh", sbvh_alpha=-1e-9), r"sbvh_alpha .*got -1e-09$"),
        (lambda: bvhlab.build(tris, method="sbvh", sbvh_budget=0.5), r"sbvh_budget .*got 0\.5$"),
        (lambda: bvhlab.build(tris, method="sbvh", sbvh_budget=64.00001), r"sbvh_budget .*got 64\.00001$"),  # %g: 64
        (lambda: bvhlab.View((0, 0, 0), (0, 1, 0), clip_start=1.0000001, clip_end=1.0), r"got 1\.0000001, 1$"),
        (lambda: bvhlab.View((0, 0, 0), (0, 1, 0), clip_start=2.0, clip_end=1.0), r"got 2, 1$"),
        (lambda: bvhlab.View((0, 0, 0), (0, 1, 0), shift_x=1500.25), r"got 1500\.25, 0$"),
        (lambda: bvhlab.RenderOptions(heatmap_scale=1e9), r"heatmap_scale .*got 1e\+09$"),
    ]
    for make, match in cases:
        with pytest.raises(ValueError, match=match):
            make()


@pytest.mark.parametrize("name", ["aspect", "ortho_scale"])
def test_a_camera_value_float32_cannot_hold_is_refused_as_given(name):
    """aspect=1e-40 was refused (its range), but 1e-50 arrived as 0, "the image's", and rendered as
    the default (probe); 1e39 arrived as inf. Both are refused by their own value now."""
    projection = "orthographic" if name == "ortho_scale" else "perspective"
    with pytest.raises(ValueError, match=f"camera {name} must be 0 or of magnitude .*got 1e-50"):
        bvhlab.View((0, 0, 0), (0, 1, 0), projection=projection, **{name: 1e-50})
    with pytest.raises(ValueError, match=rf"camera {name} must be within float32's range .*got 1e\+39"):
        bvhlab.Camera((0, 0, 0), (0, 1, 0), projection=projection, **{name: 1e39})
    bvhlab.View((0, 0, 0), (0, 1, 0), projection=projection, **{name: 2.0})
