"""A reader for the OpenEXR files Blender writes with codec NONE: scanline images, single-part or
multi-part (Blender 5 writes multilayer files as several parts), HALF or FLOAT channels. Enough to
read a render's passes back in tests without asking Blender."""

from __future__ import annotations

import struct
from pathlib import Path

import numpy as np

MAGIC = 20000630
TILED, MULTI_PART = 0x200, 0x1000
PIXEL_TYPES = {0: np.uint32, 1: np.float16, 2: np.float32}


def _header(data: bytes, offset: int) -> tuple[dict, int]:
    """Attributes (name → (type, raw bytes)) from `offset` up to the header's closing null byte."""
    attributes = {}
    while data[offset] != 0:
        name_end = data.index(b"\0", offset)
        type_end = data.index(b"\0", name_end + 1)
        name, kind = data[offset:name_end].decode(), data[name_end + 1 : type_end].decode()
        size = struct.unpack_from("<i", data, type_end + 1)[0]
        value_at = type_end + 5
        attributes[name] = (kind, data[value_at : value_at + size])
        offset = value_at + size
    return attributes, offset + 1


def _channels(raw: bytes) -> list[tuple[str, int]]:
    channels, offset = [], 0
    while raw[offset] != 0:
        end = raw.index(b"\0", offset)
        channels.append((raw[offset:end].decode(), struct.unpack_from("<i", raw, end + 1)[0]))
        offset = end + 1 + 16  # pixel type, pLinear + reserved, xSampling, ySampling
    return channels


def _headers(data: bytes, multi_part: bool) -> tuple[list[dict], int]:
    headers, offset = [], 8
    while True:
        header, offset = _header(data, offset)
        headers.append(header)
        if not multi_part or data[offset] == 0:
            return headers, offset + (1 if multi_part else 0)


def read_exr(path) -> dict[str, np.ndarray]:
    """Channel name → float32 (height, width) array, row 0 at the top of the picture."""
    data = Path(path).read_bytes()
    magic, version = struct.unpack_from("<ii", data, 0)
    if magic != MAGIC or version & TILED:
        raise ValueError(f"{path}: not a scanline OpenEXR file")
    multi_part = bool(version & MULTI_PART)
    headers, offset = _headers(data, multi_part)
    tables = []
    for header in headers:
        if header["compression"][1][0] != 0:
            raise ValueError(f"{path}: compressed (write it with codec NONE)")
        x0, y0, x1, y1 = struct.unpack("<iiii", header["dataWindow"][1])
        count = struct.unpack("<i", header["chunkCount"][1])[0] if multi_part else y1 - y0 + 1
        tables.append(struct.unpack_from(f"<{count}Q", data, offset))
        offset += 8 * count
    out = {}
    for header, table in zip(headers, tables):
        out.update(_read_part(data, header, table, multi_part))
    return out


def _read_part(data: bytes, header: dict, table, multi_part: bool) -> dict[str, np.ndarray]:
    x0, y0, x1, y1 = struct.unpack("<iiii", header["dataWindow"][1])
    width, height = x1 - x0 + 1, y1 - y0 + 1
    channels = _channels(header["channels"][1])
    out = {name: np.empty((height, width), PIXEL_TYPES[kind]) for name, kind in channels}
    for chunk in table:
        at = chunk + (4 if multi_part else 0)  # multi-part chunks start with their part number
        y, _size = struct.unpack_from("<ii", data, at)
        at += 8
        for name, kind in channels:  # one scanline of each channel, channels in name order
            dtype = np.dtype(PIXEL_TYPES[kind]).newbyteorder("<")
            out[name][y - y0] = np.frombuffer(data, dtype, width, at)
            at += width * dtype.itemsize
    return {name: a.astype(np.float32) for name, a in out.items()}
