"""Render options with values no render can use (probe): a NaN or infinite overlay line colour was
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
