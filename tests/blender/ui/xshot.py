"""The X screen as a numpy image (xwd's dump format, read here) and PNG files (zlib): no
ImageMagick needed. Blender's own screenshot operator writes black images under Xvfb/llvmpipe."""

from __future__ import annotations

import struct
import subprocess
import zlib
from pathlib import Path

import numpy as np


def capture(display: str) -> np.ndarray:
    """uint8 (height, width, 3) RGB of the whole screen, row 0 at the top."""
    raw = subprocess.run(["xwd", "-root", "-silent", "-display", display], capture_output=True, check=True).stdout
    return read_xwd(raw)


def read_xwd(raw: bytes) -> np.ndarray:
    """A ZPixmap xwd dump of 24 or 32 bits per pixel → uint8 (height, width, 3)."""
    fields = struct.unpack(">25I", raw[:100])
    header_size, _, pixmap_format, _, width, height = fields[:6]
    byte_order, bits_per_pixel, bytes_per_line = fields[7], fields[11], fields[12]
    masks, ncolors = fields[14:17], fields[19]
    if pixmap_format != 2 or bits_per_pixel not in (24, 32):
        raise ValueError(f"unsupported xwd dump: format {pixmap_format}, {bits_per_pixel} bits per pixel")
    start = header_size + 12 * ncolors
    step = bits_per_pixel // 8
    rows = np.frombuffer(raw, np.uint8, bytes_per_line * height, start).reshape(height, bytes_per_line)
    pixels = rows[:, : width * step].reshape(height, width, step).astype(np.uint32)
    order = range(step) if byte_order == 0 else range(step - 1, -1, -1)  # 0: least significant byte first
    value = sum(pixels[..., i] << (8 * k) for k, i in enumerate(order))
    channels = [(value & m) >> (int(m).bit_length() - 8) for m in masks]
    return np.stack(channels, -1).astype(np.uint8)


def write_png(path: Path, rgb: np.ndarray, text: dict[str, str] | None = None) -> None:
    """uint8 (height, width, 3) → an RGB PNG, with `text` as tEXt chunks (keyword → Latin-1 text)."""
    height, width = rgb.shape[:2]
    scanlines = b"".join(b"\0" + np.ascontiguousarray(row).tobytes() for row in rgb)

    def chunk(kind: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))

    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_bytes(
        b"\x89PNG\r\n\x1a\n"
        + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0))
        + b"".join(chunk(b"tEXt", k.encode("latin-1") + b"\0" + v.encode("latin-1")) for k, v in (text or {}).items())
        + chunk(b"IDAT", zlib.compress(scanlines, 9))
        + chunk(b"IEND", b"")
    )


def read_png_text(path: Path) -> dict[str, str]:
    """The tEXt chunks of a PNG file: keyword → text."""
    data, texts, at = path.read_bytes(), {}, 8
    while at < len(data):
        (length,), kind = struct.unpack(">I", data[at : at + 4]), data[at + 4 : at + 8]
        if kind == b"tEXt":
            keyword, _, value = data[at + 8 : at + 8 + length].partition(b"\0")
            texts[keyword.decode("latin-1")] = value.decode("latin-1")
        at += 12 + length
    return texts
