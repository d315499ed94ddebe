"""A small PNG writer (zlib only): linear float images to 8-bit sRGB, no extra dependencies."""

from __future__ import annotations

import struct
import zlib

import numpy as np

from ._atomic import write_bytes
from ._checks import output_file


def _unit(x: np.ndarray) -> np.ndarray:
    """x clipped to [0, 1], NaN as 0 (a NaN cast to uint8 is undefined: whatever the CPU gives)."""
    return np.clip(np.nan_to_num(x, nan=0.0), 0.0, 1.0)


def linear_to_srgb(x: np.ndarray) -> np.ndarray:
    x = _unit(x)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)


def straight_alpha(image: np.ndarray) -> np.ndarray:
    """A premultiplied float RGBA image (a render with film_transparent, as Blender's Render Result
    holds it) with straight alpha, as PNG stores it: colour divided by alpha where 0 < alpha < 1
    (alpha 0, 1 or not a number leaves the colour as it is)."""
    alpha = image[..., 3:4]
    between = (alpha > 0) & (alpha < 1)
    return np.concatenate([image[..., :3] / np.where(between, alpha, 1), alpha], -1).astype(np.float32)


def to_rgba8(image: np.ndarray) -> np.ndarray:
    """float (H, W, 3|4) linear → uint8 (H, W, 4) sRGB, alpha kept linear; NaN is 0, values are
    clipped to [0, 1]. An integer image is
    refused (TypeError): taken as linear floats, 8-bit values would all clip to white."""
    image = np.asarray(image)
    if not np.issubdtype(image.dtype, np.floating):
        raise TypeError(
            f"image must hold linear floats in [0, 1], got dtype {image.dtype} "
            "(for 8-bit values: image.astype(np.float32) / 255, which are sRGB, not linear)"
        )
    image = image.astype(np.float32, copy=False)
    if image.ndim != 3 or image.shape[2] not in (3, 4):
        raise ValueError(f"image must be (height, width, 3 or 4), got {image.shape}")
    if image.shape[0] == 0 or image.shape[1] == 0:  # a PNG has at least one row and column
        raise ValueError(f"image must be at least 1x1 pixels, got {image.shape[1]}x{image.shape[0]}")
    rgb = linear_to_srgb(image[..., :3])
    alpha = _unit(image[..., 3:4]) if image.shape[2] == 4 else np.ones(image.shape[:2] + (1,), np.float32)
    return (np.concatenate([rgb, alpha], 2) * 255 + 0.5).astype(np.uint8)


def write_png(image: np.ndarray, path) -> None:
    """Write `image` (see to_rgba8) to `path`, which must end in .png (OutputPathError otherwise:
    the bytes are PNG, so a .jpg name would be a lie). An old file is replaced only by a complete
    new one (WriteError naming the file otherwise)."""
    path = output_file(path, (".png",), "PNG image")
    write_bytes(path, png_bytes(image))


def png_bytes(image: np.ndarray) -> bytes:
    """`image` (see to_rgba8) as the bytes of an 8-bit RGBA PNG file."""
    rgba = to_rgba8(image)
    h, w, _ = rgba.shape
    raw = np.zeros((h, 1 + 4 * w), np.uint8)  # filter byte 0 per row
    raw[:, 1:] = rgba.reshape(h, -1)

    def chunk(tag: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + tag + data + struct.pack(">I", zlib.crc32(tag + data) & 0xFFFFFFFF)

    return (
        b"\x89PNG\r\n\x1a\n"
        + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 6, 0, 0, 0))
        + chunk(b"IDAT", zlib.compress(raw.tobytes(), 6))
        + chunk(b"IEND", b"")
    )


def save_png(image: np.ndarray, path, *, premultiplied: bool = True) -> None:
    """Write a float RGBA (or RGB) image, row 0 at the top, as an 8-bit sRGB PNG. RGBA is taken as
    premultiplied by its alpha, as bvhlab's renders give it (Film ▸ Transparent, Blender's Render
    Result), and written with straight alpha, as PNG stores it; `premultiplied=False` for an image
    whose colour is not (a render's premultiplied edge pixel of 0.06 at alpha 0.25 was written as
    69 where its colour is 135: dark fringes)."""
    write_png(_stored_colour(image, premultiplied), path)


def png_file_bytes(image: np.ndarray, *, premultiplied: bool = True) -> bytes:
    """The bytes save_png writes (for files written together: _atomic.write_together)."""
    return png_bytes(_stored_colour(image, premultiplied))


def _stored_colour(image, premultiplied: bool) -> np.ndarray:
    """`image` with the colour a PNG stores: straight alpha where it is premultiplied RGBA floats."""
    image = np.asarray(image)
    if premultiplied and image.ndim == 3 and image.shape[-1] == 4 and np.issubdtype(image.dtype, np.floating):
        image = straight_alpha(image)
    return image
