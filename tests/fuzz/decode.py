"""Prints a fuzz_core input (tests/fuzz/fuzz_input.h layout) as the arrays it stands for, to
reproduce a finding through the Python API:  python tests/fuzz/decode.py FILE"""

import struct
import sys

import numpy as np

METHODS = ("median", "mean", "midpoint", "sah", "sweep_sah", "lbvh")
AXES = ("largest", "random", "best")


def decode(data: bytes) -> dict:
    pos = 0

    def byte():
        nonlocal pos
        pos += 1
        return data[pos - 1] if pos - 1 < len(data) else 0

    kinds, bins, leaf = byte(), 2 + byte() % 255, byte()
    n_tris, n_spheres, n_rays, raw = byte() % 48, byte() % 16, byte() % 48, byte() & 1

    def value():
        if raw:
            return struct.unpack("<f", bytes(byte() for _ in range(4)))[0]
        return (byte() - 128) / 16

    tris = np.array([value() for _ in range(9 * n_tris)], np.float32).reshape(-1, 3, 3)
    spheres = np.array([value() for _ in range(4 * n_spheres)], np.float32).reshape(-1, 4)
    pairs = np.array([value() for _ in range(6 * n_rays)], np.float32).reshape(-1, 3, 2)
    offset = value()
    depth_min = byte() % 70
    return {
        "method": METHODS[kinds % 6],
        "axis": AXES[kinds // 6 % 3],
        "bins": bins,
        "max_leaf_size": 1 + leaf % 8,
        "sah_block": 1 << (leaf >> 3 & 7) % 7,
        "threads": 1 + (leaf >> 7),
        "triangles": tris,
        "spheres": spheres,
        "origins": pairs[..., 0].copy(),
        "directions": pairs[..., 1].copy(),
        "refit_offset": np.float32(offset),
        "depth_range": (depth_min, depth_min + byte() % 8),
    }


if __name__ == "__main__":
    np.set_printoptions(precision=9, threshold=100000)
    for key, value in decode(open(sys.argv[1], "rb").read()).items():
        print(f"{key} = {value!r}")
