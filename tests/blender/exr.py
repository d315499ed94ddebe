"""A reader for the OpenEXR files Blender writes with codec NONE: single-part scanline images,
HALF or FLOAT channels (enough to read a multilayer EXR's passes back in tests, independently
of Blender)."""
from __future__ import annotations

import struct
from pathlib import Path

import numpy as np

MAGIC = 20000630
PIXEL_TYPES = {1: np.float16, 2: np.float32, 0: np.uint32}


def _attributes(data: bytes, offset: int) -> tuple[dict, int]:
    attributes = {}
    while data[offset] != 0:
        name_end = data.index(b"\0", offset)
        type_end = data.index(b"\0", name_end + 1)
        name, kind = data[offset:name_end].decode(), data[name_end + 1:type_end].decode()
        size = struct.unpack_from("<i", data, type_end + 1)[0]
        value_at = type_end + 5
        attributes[name] = (kind, data[value_at:value_at + size])
        offset = value_at + size
    return attributes, offset + 1


def _channels(raw: bytes) -> list[tuple[str, int]]:
    channels, offset = [], 0
    while raw[offset] != 0:
        end = raw.index(b"\0", offset)
        pixel_type = struct.unpack_from("<i", raw, end + 1)[0]
        channels.append((raw[offset:end].decode(), pixel_type))
        offset = end + 1 + 16
    return channels


def read_exr(path) -> dict[str, np.ndarray]:
    """Channel name → (height, width) array, row 0 at the top of the picture."""
    data = Path(path).read_bytes()
    magic, version = struct.unpack_from("<ii", data, 0)
    if magic != MAGIC or version & 0x1200:  # tiled or multi-part
        raise ValueError(f"{path}: not a single-part scanline OpenEXR file")
    attributes, offset = _attributes(data, 8)
    if attributes["compression"][1][0] != 0:
        raise ValueError(f"{path}: compressed (write it with codec NONE)")
    x0, y0, x1, y1 = struct.unpack("<iiii", attributes["dataWindow"][1])
    width, height = x1 - x0 + 1, y1 - y0 + 1
    channels = _channels(attributes["channels"][1])
    offsets = struct.unpack_from(f"<{height}Q", data, offset)
    out = {name: np.empty((height, width), PIXEL_TYPES[kind]) for name, kind in channels}
    for line_offset in offsets:
        y, _size = struct.unpack_from("<ii", data, line_offset)
        at = line_offset + 8
        for name, kind in channels:
            dtype = np.dtype(PIXEL_TYPES[kind]).newbyteorder("<")
            out[name][y - y0] = np.frombuffer(data, dtype, width, at)
            at += width * dtype.itemsize
    return {name: a.astype(np.float32) for name, a in out.items()}
