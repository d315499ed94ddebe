"""Arguments several commands share, parsed once."""
from __future__ import annotations

import argparse

from ..bvh import AXES, DEFAULT_AXIS, DEFAULT_BINS, DEFAULT_MAX_LEAF_SIZE, DEFAULT_METHOD, METHODS, method_from_label


def add_scene(p: argparse.ArgumentParser) -> None:
    p.add_argument("scene", metavar="SCENE", help="a .blend or .npz file, or a scene name from `bvhlab scenes`")


def add_build(p: argparse.ArgumentParser) -> None:
    p.add_argument("--method", default=DEFAULT_METHOD, help=f"split method: {', '.join(METHODS)} (or sah<B>, e.g. sah32)")
    p.add_argument("--bins", type=int, default=None, help=f"binned SAH buckets, 2..256 (default {DEFAULT_BINS})")
    p.add_argument("--axis", default=DEFAULT_AXIS, choices=AXES, help=f"split axis policy (default {DEFAULT_AXIS})")
    p.add_argument("--max-leaf-size", type=int, default=DEFAULT_MAX_LEAF_SIZE,
                   help=f"primitives per leaf at most (default {DEFAULT_MAX_LEAF_SIZE})")


def build_kwargs(args) -> dict:
    kw = method_kwargs(args.method)
    if args.bins is not None:
        kw["bins"] = args.bins
    return {**kw, "axis": args.axis, "max_leaf_size": args.max_leaf_size}


method_kwargs = method_from_label


def depth_range(text: str) -> tuple[int, int]:
    """'8:9' → (8, 9); '3' → (3, 3)."""
    try:
        a, _, b = text.partition(":")
        lo, hi = int(a), int(b or a)
    except ValueError:
        raise argparse.ArgumentTypeError(f"depth range must look like A:B (e.g. 8:9), got '{text}'") from None
    if lo < 0 or hi < lo:
        raise argparse.ArgumentTypeError(f"depth range {text}: need 0 <= A <= B")
    return lo, hi
