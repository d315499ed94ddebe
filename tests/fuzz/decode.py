"""Prints a fuzz_core input (tests/fuzz/fuzz_input.h layout) as the arrays it stands for, to
reproduce a finding through the Python API:  python tests/fuzz/decode.py FILE"""

import struct
import sys

import numpy as np

METHODS = ("median", "mean", "midpoint", "sah", "sweep_sah", "lbvh")  # byte 0 % 6; sbvh: byte 6 bit 1
AXES = ("largest", "random", "best")
SBVH_BUDGETS = (1.5, 1.0, 1.1, 1.25, 2.0, 3.0, 8.0, 64.0)  # fuzz_input.h kBudgets
SBVH_ALPHAS = (3e-4, 0.0, 1e-2, 1.0)  # kAlphas


def decode(data: bytes) -> dict:
    pos = 0

    def byte():
        nonlocal pos
        pos += 1
        return data[pos - 1] if pos - 1 < len(data) else 0

    kinds, bins, leaf = byte(), 2 + byte() % 255, byte()
    n_tris, n_spheres, n_rays, encoding = byte() % 48, byte() % 16, byte() % 48, byte()
    raw = encoding & 1

    def value():
        if raw:
            return struct.unpack("<f", bytes(byte() for _ in range(4)))[0]
        return (byte() - 128) / 16

    tris = np.array([value() for _ in range(9 * n_tris)], np.float32).reshape(-1, 3, 3)
    spheres = np.array([value() for _ in range(4 * n_spheres)], np.float32).reshape(-1, 4)
    pairs = np.array([value() for _ in range(6 * n_rays)], np.float32).reshape(-1, 3, 2)
    offset = value()
    depth_min = byte() % 70
    sbvh = {}
    if encoding & 2:
        sbvh = {
            "sbvh_budget": SBVH_BUDGETS[encoding >> 2 & 7],
            "sbvh_alpha": SBVH_ALPHAS[encoding >> 5 & 3],
            "sbvh_unsplit": not encoding & 0x80,
        }
    return {
        "method": "sbvh" if sbvh else METHODS[kinds % 6],
        **sbvh,
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
