"""Arguments several commands share, parsed once."""

from __future__ import annotations

import argparse
import math
import re
from collections.abc import Callable
from pathlib import Path

import numpy as np

from .. import _core
from .._checks import MAX_DEPTH, OutputPathError, output_file
from .._progress import ProgressBar, Ticker
from ..build_config import (
    AXES,
    BIN_BOUNDS,
    DEFAULT_AXIS,
    DEFAULT_BIN_BOUNDS,
    DEFAULT_BINS,
    DEFAULT_MAX_LEAF_SIZE,
    DEFAULT_METHOD,
    DEFAULT_SAH_BLOCK,
    MAX_BINS,
    MAX_LEAF_SIZE,
    MAX_SAH_BLOCK,
    METHODS,
    MIN_BINS,
    label_settings,
)
from ..bvh import (
    Bvh,
    build,
)
from ..library import FILE_KINDS, is_scene_file
from ..optimize import OptimizeConfig, OptimizeStats
from ..render_options import DEFAULT_HEIGHT, DEFAULT_WIDTH

#: Largest image side the CLI accepts (OpenGL's and most Vulkan drivers' framebuffer limit).
MAX_IMAGE_SIDE = _core.MAX_IMAGE_DIMENSION  # the renderers' limit, one definition


def add_scene(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "scene",
        type=scene_spec,
        metavar="SCENE",
        help="a scene file (.blend, .npz, .obj, .ply, .stl, .gltf, .glb), or a scene name from `bvhlab scenes`",
    )


def scene_spec(text: str) -> str:
    """A SCENE argument. A scene file (library.is_scene_file: by its suffix, in any case, as the
    loader reads them) that exists but is not a regular file (a FIFO, which would block the reader until someone
    writes to it, a device, a folder) is refused before any work; names, and files that do not
    exist, are left to the loader, which lists the names."""
    path = Path(text)
    if not is_scene_file(text):
        return text
    if path.is_dir():
        raise argparse.ArgumentTypeError(f"{text} is a folder; give a scene file ({FILE_KINDS})")
    if path.exists() and not path.is_file():
        raise argparse.ArgumentTypeError(
            f"{text} is not a regular file (a FIFO, device or socket); give a scene file ({FILE_KINDS})"
        )
    return text


def read_scene(spec: str):
    """library.load_scene with the time it takes shown on a terminal (Ticker): a scene file of
    millions of triangles reads for seconds before the build's bar."""
    from ..library import load_scene, scene_file

    path = scene_file(spec)
    if path is None or not path.is_file():
        return load_scene(spec)
    size = path.stat().st_size
    with Ticker(f"reading {path.name} ({size / 1e6:.0f} MB)" if size >= 1e6 else f"reading {path.name}"):
        return load_scene(spec)


def add_build(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--method", default=DEFAULT_METHOD, help=f"split method: {', '.join(METHODS)} (or sah<B>, e.g. sah32)"
    )
    p.add_argument(
        "--bins",
        type=lambda text: whole_number(text, MIN_BINS, MAX_BINS),
        default=None,
        help=f"binned SAH buckets, {MIN_BINS}..{MAX_BINS} (default {DEFAULT_BINS})",
    )
    p.add_argument(
        "--bin-bounds",
        default=DEFAULT_BIN_BOUNDS,
        choices=BIN_BOUNDS,
        help=f"what the SAH buckets divide: the node's box or its centroid bounds (default {DEFAULT_BIN_BOUNDS})",
    )
    p.add_argument("--axis", default=DEFAULT_AXIS, choices=AXES, help=f"split axis policy (default {DEFAULT_AXIS})")
    p.add_argument(
        "--max-leaf-size",
        type=lambda text: whole_number(text, 1, MAX_LEAF_SIZE),
        default=DEFAULT_MAX_LEAF_SIZE,
        help=f"primitives per leaf at most (default {DEFAULT_MAX_LEAF_SIZE})",
    )
    p.add_argument(
        "--sah-block",
        type=sah_block,
        default=DEFAULT_SAH_BLOCK,
        help=f"the SAH counts primitives in blocks of this many, a power of two up to {MAX_SAH_BLOCK} "
        f"(default {DEFAULT_SAH_BLOCK}, the report's SAH; 4: the triangles the CPU traversal tests at once)",
    )


def add_optimize(p: argparse.ArgumentParser) -> None:
    """--optimize N and --optimize-ms MS: Bvh.optimize after the build (OptimizeConfig)."""
    p.add_argument(
        "--optimize",
        type=lambda text: whole_number(text, 0, 2**32 - 1),
        default=0,
        metavar="N",
        help="after the build, optimise the tree by reinsertion (Bittner et al. 2013) for at most N batches "
        "(default 0: not at all)",
    )
    p.add_argument(
        "--optimize-ms",
        type=milliseconds,
        default=0.0,
        metavar="MS",
        help="with --optimize: stop after this many ms, keeping what it did (default 0: no budget)",
    )


def optimize_config(args) -> OptimizeConfig | None:
    """The OptimizeConfig of --optimize/--optimize-ms (checked, ValueError), or None without --optimize
    (--optimize-ms alone is refused: it bounds an optimisation that would not run)."""
    if args.optimize_ms and not args.optimize:
        raise ValueError("--optimize-ms bounds --optimize N's optimisation: give --optimize N too")
    try:
        config = OptimizeConfig(iterations=args.optimize, time_budget_ms=args.optimize_ms)
    except ValueError as e:  # named by the options typed (it said time_budget_ms)
        text = str(e).replace("time_budget_ms", "--optimize-ms").replace("iterations", "--optimize")
        raise ValueError(text) from None
    return config if args.optimize else None


#: Why --optimize refuses a scene with instances: its TLAS holds the meshes' trees as built.
OPTIMIZE_FLAT_ONLY = "--optimize takes a flat scene's tree; this scene has instances (a two-level tree)"


def optimize_tree(bvh, config: OptimizeConfig | None) -> OptimizeStats | None:
    """`bvh` optimised as --optimize asks (with a progress bar), and what that did; None when not
    asked. A two-level tree is refused (ValueError, OPTIMIZE_FLAT_ONLY)."""
    if config is None:
        return None
    if not isinstance(bvh, Bvh):
        raise ValueError(OPTIMIZE_FLAT_ONLY)
    with ProgressBar("optimizing") as bar:
        return bvh.optimize(config, progress=bar)


def typed_build_options(p: argparse.ArgumentParser) -> None:
    """add_build's options with no default: run() tells the ones typed (not None) from the rest,
    then fills those with fill_build_defaults."""
    p.set_defaults(**dict.fromkeys(BUILD_DEFAULTS))


#: add_build's defaults, by option.
BUILD_DEFAULTS = {
    "method": DEFAULT_METHOD,
    "bins": None,
    "axis": DEFAULT_AXIS,
    "bin_bounds": DEFAULT_BIN_BOUNDS,
    "max_leaf_size": DEFAULT_MAX_LEAF_SIZE,
    "sah_block": DEFAULT_SAH_BLOCK,
}


def fill_build_defaults(args) -> dict:
    """The build settings typed on a command line of typed_build_options (their BuildConfig fields
    and values: `sah32` gives method and bins), the rest set to add_build's defaults in `args`."""
    typed: dict = {}
    if args.method is not None:
        typed |= label_settings(args.method, args.bins)
    elif args.bins is not None:
        typed["bins"] = args.bins
    for name in ("axis", "bin_bounds", "max_leaf_size", "sah_block"):
        if getattr(args, name) is not None:
            typed[name] = getattr(args, name)
    for name, default in BUILD_DEFAULTS.items():
        if getattr(args, name) is None:
            setattr(args, name, default)
    return typed


def build_kwargs(args) -> dict:
    """The build arguments of the command line, checked (ValueError) before any work is done."""
    kw = label_settings(args.method, args.bins)
    return checked_build_kwargs(
        {
            **kw,
            "axis": args.axis,
            "bin_bounds": args.bin_bounds,
            "max_leaf_size": args.max_leaf_size,
            "sah_block": args.sah_block,
        }
    )


def checked_build_kwargs(kwargs: dict) -> dict:
    """`kwargs` checked by `bvhlab.build` itself, on no primitives (microseconds): a bad value (sah1's
    one bin, a leaf size of 0) is refused with build's own message before a scene is loaded or a
    measurement starts, and no second copy of its limits can drift from the first."""
    build(np.zeros((0, 3, 3), np.float32), **kwargs)
    return kwargs


def add_image_size(p: argparse.ArgumentParser, defaults: bool = True) -> None:
    """--width and --height of the image (by default the core's, 800 × 600: the report's; None with
    `defaults` False, for a command that tells whether they were given)."""
    p.add_argument("--width", type=image_side, default=DEFAULT_WIDTH if defaults else None)
    p.add_argument("--height", type=image_side, default=DEFAULT_HEIGHT if defaults else None)


def add_png_out(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--out",
        type=output_file_type(".png", "PNG image"),
        required=True,
        help="PNG file to write (the name must end in .png)",
    )


def depth_range(text: str) -> tuple[int, int]:
    """'8:9' → (8, 9); '3' → (3, 3)."""
    try:
        a, _, b = text.partition(":")
        lo, hi = int(a), int(b or a)
    except ValueError:
        raise argparse.ArgumentTypeError(f"depth range must look like A:B (e.g. 8:9), got '{text}'") from None
    if lo < 0 or hi < lo:
        raise argparse.ArgumentTypeError(f"depth range {text}: need 0 <= A <= B")
    if hi > MAX_DEPTH:  # the boxes' and the overlay's bound, checked before any work (it came after
        # the scene's load and build, as "depth_min must be between 0 and 255": a helper's audit)
        raise argparse.ArgumentTypeError(f"depth range {text}: depths go up to {MAX_DEPTH}")
    return lo, hi


def whole_number(text: str, lo: int | None = None, hi: int | None = None, unit: str = "") -> int:
    """An argparse value: an integer, in lo..hi when they are given (unit, e.g. " pixels", only
    for the message), checked before any work."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number{unit and ' of' + unit}, got '{text}'") from None
    if lo is not None and hi is not None and not lo <= value <= hi:
        raise argparse.ArgumentTypeError(f"must be between {lo} and {hi}{unit}, got {value}")
    return value


def sah_block(text: str) -> int:
    """An argparse value: --sah-block's power of two, 1..MAX_SAH_BLOCK (the core's check named the
    setting `sah_block`, which the command line does not use)."""
    value = whole_number(text)
    if not (1 <= value <= MAX_SAH_BLOCK and value & (value - 1) == 0):
        raise argparse.ArgumentTypeError(f"must be a power of two from 1 to {MAX_SAH_BLOCK}, got {value}")
    return value


def milliseconds(text: str) -> float:
    """An argparse value: a finite number of ms, at least 0 (the core's check said "time_budget_ms",
    a name the command line does not use)."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number of ms, got '{text}'") from None
    if not (math.isfinite(value) and value >= 0):
        raise argparse.ArgumentTypeError(f"must be a finite number of ms, at least 0 (0: no budget), got {text}")
    return value


def image_side(text: str) -> int:
    """An image width or height: 1..MAX_IMAGE_SIDE pixels."""
    return whole_number(text, 1, MAX_IMAGE_SIDE, " pixels")


def samples_per_axis(text: str) -> int:
    """n of the n×n supersampling: 1..MAX_SAMPLES_PER_AXIS."""
    return whole_number(text, 1, _core.MAX_SAMPLES_PER_AXIS)


def output_file_type(suffix: str, what: str) -> Callable[[str], Path]:
    """An argparse type: a file path to be written, ending in `suffix`, checked before any work
    (not a folder, not under a file, never renamed)."""

    def parse(text: str) -> Path:
        try:
            return output_file(text, (suffix,), what)
        except OutputPathError as e:
            raise argparse.ArgumentTypeError(str(e)) from None

    return parse


#: Options whose value may start with '-' (a depth range such as -1:2 or a pixel such as -1,5
#: would otherwise be taken for an option by argparse, which then says "expected one argument"
#: instead of what is wrong).
_DASH_VALUE_OPTIONS = ("--bvh-depth", "--pixel", "--range", "--frames")


def join_dash_values(argv: list[str]) -> list[str]:
    """['--bvh-depth', '-1:2'] → ['--bvh-depth=-1:2'] (and '--pixel -1,5', '--range -1,5',
    '--frames -1-2'), so the value's own check explains, or takes it."""
    out: list[str] = []
    for arg in argv:
        if out and out[-1] in _DASH_VALUE_OPTIONS and re.fullmatch(r"-[\d.eE+:,-]+", arg):
            out[-1] = f"{out[-1]}={arg}"
        else:
            out.append(arg)
    return out
