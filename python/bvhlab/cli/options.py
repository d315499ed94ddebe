"""Arguments several commands share, parsed once."""
from __future__ import annotations

import argparse

from ..bvh import AXES, METHODS, method_from_label


def add_scene(p: argparse.ArgumentParser) -> None:
    p.add_argument("scene", metavar="SCENE", help="a .blend or .npz file, or a scene name from `bvhlab scenes`")


def add_build(p: argparse.ArgumentParser) -> None:
    p.add_argument("--method", default="sah", help=f"split method: {', '.join(METHODS)} (or sah<B>, e.g. sah32)")
    p.add_argument("--bins", type=int, default=None, help="binned SAH buckets, 2..256 (default 12)")
    p.add_argument("--axis", default="largest", choices=AXES, help="split axis policy")
    p.add_argument("--max-leaf-size", type=int, default=1, help="primitives per leaf at most (default 1)")


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
