"""A small PNG writer (zlib only): linear float images to 8-bit sRGB, no extra dependencies."""

from __future__ import annotations

import struct
import zlib

import numpy as np

from ._atomic import write_bytes
from ._checks import output_file


def linear_to_srgb(x: np.ndarray) -> np.ndarray:
    x = np.clip(x, 0.0, 1.0)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)


def to_rgba8(image: np.ndarray) -> np.ndarray:
    """float (H, W, 3|4) linear → uint8 (H, W, 4) sRGB, alpha kept linear."""
    image = np.asarray(image, np.float32)
    if image.ndim != 3 or image.shape[2] not in (3, 4):
        raise ValueError(f"image must be (height, width, 3 or 4), got {image.shape}")
    rgb = linear_to_srgb(image[..., :3])
    alpha = np.clip(image[..., 3:4], 0, 1) if image.shape[2] == 4 else np.ones(image.shape[:2] + (1,), np.float32)
    return (np.concatenate([rgb, alpha], 2) * 255 + 0.5).astype(np.uint8)


def write_png(image: np.ndarray, path) -> None:
    """Write `image` (see to_rgba8) to `path`, which must end in .png (OutputPathError otherwise:
    the bytes are PNG, so a .jpg name would be a lie). An old file is replaced only by a complete
    new one (WriteError naming the file otherwise)."""
    path = output_file(path, (".png",), "PNG image")
    rgba = to_rgba8(image)
    h, w, _ = rgba.shape
    raw = np.zeros((h, 1 + 4 * w), np.uint8)  # filter byte 0 per row
    raw[:, 1:] = rgba.reshape(h, -1)

    def chunk(tag: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + tag + data + struct.pack(">I", zlib.crc32(tag + data) & 0xFFFFFFFF)

    png = (
        b"\x89PNG\r\n\x1a\n"
        + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 6, 0, 0, 0))
        + chunk(b"IDAT", zlib.compress(raw.tobytes(), 6))
        + chunk(b"IEND", b"")
    )
    write_bytes(path, png)
