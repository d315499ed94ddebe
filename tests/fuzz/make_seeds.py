"""Writes the seed corpus of fuzz_core (tests/fuzz/corpus): small cases of each kind, in the byte
layout of fuzz_input.h. Run it again after changing that layout; the fuzzer grows the rest."""

import struct
from pathlib import Path

CORPUS = Path(__file__).resolve().parent / "corpus"


def grid(x: float) -> bytes:
    """A grid value (encoding 0): -8 .. 7.9375 in steps of 1/16."""
    return bytes([max(0, min(255, round(x * 16) + 128))])


def raw(x: float) -> bytes:
    return struct.pack("<f", x)


def case(method, axis, bins, leaf, threads, tris, spheres, rays, encoding, extra=b""):
    put = raw if encoding else grid
    head = bytes(
        [
            method + 6 * axis,
            bins - 2,
            (leaf - 1) | (0x80 if threads == 2 else 0),
            len(tris),
            len(spheres),
            len(rays),
            encoding,
        ]
    )
    body = b"".join(put(x) for t in tris for v in t for x in v)
    body += b"".join(put(x) for s in spheres for x in s)
    # fuzz_input.h reads each ray's origin and direction component by component, interleaved
    body += b"".join(put(oc) + put(dc) for origin, direction in rays for oc, dc in zip(origin, direction))
    return head + body + extra


def sbvh(encoding, budget=0, alpha=0, unsplit=True):
    """Byte 6 for method sbvh (fuzz_input.h): the float encoding, kBudgets[budget], kAlphas[alpha]."""
    return encoding | 2 | budget << 2 | alpha << 5 | (0 if unsplit else 0x80)


SQUARE = [[(0, 0, 0), (1, 0, 0), (1, 1, 0)], [(0, 0, 0), (1, 1, 0), (0, 1, 0)]]
DOWN = [((x, y, 1), (0, 0, -1)) for x in (0, 0.5, 1) for y in (0, 0.5, 1)]
STACK = [[(-1, -1, z), (3, -1, z), (-1, 3, z)] for z in range(-3, 4)]
SPHERES = [(0, 0, 0, 1), (2, 0, 0, 0.5), (0, 2, 0, 0.25), (0, 0, 2, 2)]
# long thin triangles across each other: spatial splits pay (the SBVH seeds)
RODS = [[(-8, y, z), (7.5, -y, 1 - z), (7.5, 0.25 - y, 1 - z)] for y in (-3, 0, 3) for z in (-2, 0.5, 2)]
RANDOM_RAYS = [((-4 + i, 0.3 * i - 2, 5), (0.1 * i - 1, 0.2, -1)) for i in range(8)]

SEEDS = {
    "square_edges": case(3, 0, 12, 1, 1, SQUARE, [], DOWN, 0, grid(0.5) + bytes([0, 3])),
    "stacked_ties": case(0, 0, 12, 2, 2, STACK + STACK, [], [((0, 0, -6), (0, 0, 1)), ((0.5, 0.5, 6), (0, 0, -1))], 0),
    "spheres": case(4, 2, 12, 1, 1, [], SPHERES, RANDOM_RAYS, 0, grid(1.0) + bytes([1, 2])),
    "mixed_lbvh": case(5, 0, 12, 3, 2, SQUARE + STACK, SPHERES, RANDOM_RAYS, 0),
    "random_axis": case(1, 1, 7, 1, 1, STACK, SPHERES[:2], RANDOM_RAYS, 0),
    "raw_huge": case(
        3,
        0,
        12,
        1,
        1,
        [[(0, 0, 0), (1e12, 0, 0), (0, 1e12, 0)], [(0, 0, 0), (1e13, 0, 0), (0, 1, 0)]],
        [],
        [((0, 0, 1), (0, 0, -1))],
        1,
    ),
    "raw_tiny_directions": case(
        3,
        2,
        30,
        1,
        1,
        SQUARE,
        SPHERES[:1],
        [((0.25, 0.25, 3), (0, 0, -1e-22)), ((0.25, 0.25, 3), (0, 0, -1e22)), ((0, 0, 3), (0, 0, -1e-30))],
        1,
        raw(5.0),
    ),
    "raw_nan": case(0, 0, 12, 1, 2, SQUARE, [(0, 0, 0, float("nan"))], DOWN[:2], 1),
    "empty": case(3, 0, 12, 1, 1, [], [], DOWN[:1], 0),
    "sbvh_rods": case(3, 2, 12, 1, 1, RODS + SQUARE, [], RANDOM_RAYS + DOWN, sbvh(0, budget=7, alpha=1)),
    "sbvh_mixed": case(3, 0, 8, 3, 2, RODS + STACK, SPHERES, RANDOM_RAYS, sbvh(0), grid(0.5) + bytes([0, 4])),
    "sbvh_raw_no_unsplit": case(
        3,
        0,
        16,
        2,
        1,
        [[(-1e6, 0, 0), (1e6, 1, 0), (1e6, 0, 1e-30)], [(0, -1e6, 3), (1, 1e6, -3), (0, 1e6, 0)]] + SQUARE,
        [(0, 0, 0, 1e-10)],
        [((0.25, 0.25, 3), (0, 0, -1)), ((5e5, 0.5, 3), (0, 0, -1))],
        sbvh(1, budget=4, alpha=1, unsplit=False),
    ),
}

if __name__ == "__main__":
    CORPUS.mkdir(exist_ok=True)
    for name, data in SEEDS.items():
        (CORPUS / name).write_bytes(data)
    print(f"wrote {len(SEEDS)} seeds to {CORPUS}")
