"""Reading back the PNGs bvhlab writes (8-bit RGBA, no interlace, filter 0): a test helper, so
the package keeps only the writer."""

from __future__ import annotations

import struct
import zlib
from pathlib import Path

import numpy as np


def read_png(path) -> np.ndarray:
    """Read back a PNG written by write_png (8-bit RGBA, no interlace, filter 0): uint8 (H, W, 4)."""
    data = Path(path).read_bytes()
    if data[:8] != b"\x89PNG\r\n\x1a\n":
        raise ValueError(f"{path} is not a PNG")
    pos, idat, size = 8, b"", (0, 0)
    while pos < len(data):
        (length,) = struct.unpack(">I", data[pos : pos + 4])
        tag = data[pos + 4 : pos + 8]
        body = data[pos + 8 : pos + 8 + length]
        if tag == b"IHDR":
            w, h, depth, ctype = struct.unpack(">IIBB", body[:10])
            if (depth, ctype) != (8, 6):
                raise ValueError("only 8-bit RGBA PNGs are read")
            size = (h, w)
        elif tag == b"IDAT":
            idat += body
        pos += 12 + length
    h, w = size
    raw = np.frombuffer(zlib.decompress(idat), np.uint8).reshape(h, 1 + 4 * w)
    if np.any(raw[:, 0]):
        raise ValueError("only unfiltered PNGs are read")
    return raw[:, 1:].reshape(h, w, 4).copy()
