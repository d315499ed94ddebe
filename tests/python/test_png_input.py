"""`bvhlab.save_png` on images it cannot write as asked (probe): an 8-bit image was read as linear
floats (every pixel clipped to white) and an empty one raised a numpy reshape error or, 0 wide,
wrote a PNG of width 0 that no reader opens."""

import numpy as np
import pytest
from png_reader import read_png  # the tests' own PNG reader (tests/python/png_reader.py)

import bvhlab


@pytest.mark.parametrize("dtype", [np.uint8, np.uint16, np.int32, np.bool_])
def test_an_integer_image_is_refused(tmp_path, dtype):
    image = np.full((4, 5, 3), 100, dtype) if dtype != np.bool_ else np.ones((4, 5, 3), bool)
    with pytest.raises(TypeError, match="linear floats"):
        bvhlab.save_png(image, tmp_path / "x.png")
    assert not (tmp_path / "x.png").exists()


@pytest.mark.parametrize("shape", [(0, 0, 4), (0, 5, 4), (5, 0, 3)])
def test_an_empty_image_is_refused(tmp_path, shape):
    with pytest.raises(ValueError, match="at least 1x1"):
        bvhlab.save_png(np.zeros(shape, np.float32), tmp_path / "x.png")
    assert not (tmp_path / "x.png").exists()


def test_float_images_are_written_as_before(tmp_path):
    image = np.zeros((2, 3, 4), np.float64)
    image[..., 0], image[..., 3] = 1.0, 1.0
    bvhlab.save_png(image, tmp_path / "x.png")
    rgba = read_png(tmp_path / "x.png")
    assert rgba.shape[:2] == (2, 3) and (rgba[..., 0] == 255).all() and (rgba[..., 1] == 0).all()


def test_nan_and_infinite_pixels_are_written_as_defined_bytes(tmp_path):
    """NaN is 0 and ±inf clips to 1 and 0, in colour and alpha: a NaN cast to uint8 was whatever
    the CPU gave (0 on x86, with a RuntimeWarning)."""
    image = np.full((1, 4, 4), 0.5, np.float32)
    image[0, 0] = np.nan
    image[0, 1] = np.inf
    image[0, 2] = -np.inf
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no "invalid value encountered in cast"
        bvhlab.save_png(image, tmp_path / "x.png", premultiplied=False)
    pixels = read_png(tmp_path / "x.png")
    assert pixels[0, 0].tolist() == [0, 0, 0, 0]
    assert pixels[0, 1].tolist() == [255, 255, 255, 255]
    assert pixels[0, 2].tolist() == [0, 0, 0, 0]
    assert pixels[0, 3].tolist() == [188, 188, 188, 128]  # 0.5 linear is 188 in sRGB


def _srgb8(linear: float) -> int:
    """The sRGB transfer function (IEC 61966-2-1), rounded to 8 bits."""
    s = 12.92 * linear if linear <= 0.0031308 else 1.055 * linear ** (1 / 2.4) - 0.055
    return int(s * 255 + 0.5)


def test_a_premultiplied_render_is_written_with_straight_alpha(tmp_path):
    """A render with Film ▸ Transparent is premultiplied (colour × coverage): its edge pixel of
    0.06 at alpha 0.25 is colour 0.24 (it was written as 0.06: dark fringes); opaque and empty
    pixels as they are; premultiplied=False writes the colour as given."""
    image = np.zeros((1, 3, 4), np.float32)
    image[0, 0] = (0.06, 0.06, 0.06, 0.25)
    image[0, 1] = (0.5, 0.25, 0.1, 1.0)
    image[0, 2] = (0.0, 0.0, 0.0, 0.0)
    bvhlab.save_png(image, tmp_path / "p.png")
    pixels = read_png(tmp_path / "p.png")
    assert pixels[0, 0].tolist() == [_srgb8(0.24)] * 3 + [64]
    assert pixels[0, 1].tolist() == [_srgb8(0.5), _srgb8(0.25), _srgb8(0.1), 255]
    assert pixels[0, 2].tolist() == [0, 0, 0, 0]
    bvhlab.save_png(image, tmp_path / "s.png", premultiplied=False)
    assert read_png(tmp_path / "s.png")[0, 0].tolist() == [_srgb8(0.06)] * 3 + [64]
