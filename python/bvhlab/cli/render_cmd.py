"""`bvhlab render SCENE --out PNG`: build a tree and render the scene with the Whitted tracer,
optionally with the BVH overlay (--bvh-depth A:B; a legend of its depth colours under the image),
or a traversal counter per pixel (--counter NAME: the false-colour image with its scale bar, the
raw counts per primary ray beside it as OUT.npy, their histogram as OUT.histogram.png and
OUT.histogram.json; --heatmap is --counter box_tests)."""

from __future__ import annotations

import argparse
import io
import sys
from pathlib import Path

import numpy as np

from .. import Bvh, InstancedBvh, _core, build, counters, histogram, legend, save_png
from .. import _json as strict_json
from .._atomic import write_together
from .._checks import OutputPathError
from .._progress import ProgressBar
from ..png import png_file_bytes, straight_alpha
from ..render import BACKENDS, default_renderer
from ..render_options import AUTO_TRAVERSAL, RENDER_TRAVERSALS, RenderOptions
from . import options

_DEFAULT = RenderOptions()  # the defaults are the core's (one definition)


def add_parser(sub) -> None:
    p = sub.add_parser("render", help="render a scene to a PNG", description=__doc__)
    options.add_scene(p)
    options.add_build(p)
    options.add_image_size(p)
    p.add_argument(
        "--backend", default="auto", choices=BACKENDS, help="auto (a Vulkan GPU, else the CPU reference), vulkan or cpu"
    )
    p.add_argument(
        "--samples-per-axis",
        type=options.samples_per_axis,
        default=_DEFAULT.samples_per_axis,
        metavar="N",
        help=f"N×N samples per pixel (default {_DEFAULT.samples_per_axis})",
    )
    p.add_argument(
        "--max-depth",
        type=lambda text: options.whole_number(text, 0, int(_core.MAX_RAY_DEPTH)),
        default=_DEFAULT.max_depth,
        help=f"bounces of reflection and refraction (default {_DEFAULT.max_depth})",
    )
    p.add_argument("--bvh-depth", type=options.depth_range, metavar="A:B", help="draw the boxes of depths A..B")
    p.add_argument(
        "--counter",
        choices=counters.COUNTERS,
        help="colour pixels by a traversal counter of their primary rays (averaged over the samples); "
        "writes the counts as OUT.npy too",
    )
    p.add_argument(
        "--range",
        type=_range,
        default=None,
        metavar="LO,HI|auto",
        help=f"the counter's colour range (default auto: 0 to the {counters.AUTO_PERCENTILE:g}th percentile)",
    )
    p.add_argument("--heatmap", action="store_true", help="the same as --counter box_tests (kept for old scripts)")
    p.add_argument(
        "--traversal",
        default=AUTO_TRAVERSAL,
        choices=RENDER_TRAVERSALS,
        help="stack or stackless (report §3.1), wide: the CPU tracer through the tree's 8-wide copy, the "
        "same image faster, or auto (the default): wide on the CPU, stack on a GPU and with --counter",
    )
    p.add_argument(
        "--film-transparent",
        action="store_true",
        help="Blender's Film ▸ Transparent: alpha is the share of a pixel's camera rays that hit something "
        "(the sky transparent)",
    )
    options.add_png_out(p)
    p.set_defaults(run=run)


def _range(text: str):
    try:
        return counters.parse_range(text)
    except ValueError as e:
        raise argparse.ArgumentTypeError(str(e)) from None


def run(args) -> int:
    settings = options.build_kwargs(args)  # checked before the scene is loaded
    counter = _counter(args)
    render_options = RenderOptions(  # likewise
        samples_per_axis=args.samples_per_axis,
        max_depth=args.max_depth,
        overlay_depth=args.bvh_depth,
        traversal=args.traversal,
        traversal_counters=counter is not None,
        film_transparent=args.film_transparent,
    )
    if counter is not None:  # the files written beside OUT (its folder checked with it), before any work
        for path in counter_paths(args.out):
            if path.exists() and not path.is_file():
                raise OutputPathError(
                    f"{path} is a folder or not a regular file; --counter writes the counts and their "
                    f"histogram beside --out {args.out} there: move it, or give another --out"
                )
    scene, name = options.read_scene(args.scene)
    with ProgressBar(f"building {args.method}") as bar:
        bvh = build(scene, progress=bar, **settings)  # an instanced scene: a two-level tree, rendered as it is
    warning = legend.no_boxes_warning(legend.overlay_height(bvh), args.bvh_depth) if args.bvh_depth else None
    if warning:  # drew nothing, silently
        print(warning, file=sys.stderr)
    renderer = default_renderer(args.backend)
    with ProgressBar("rendering") as bar:
        job = renderer.start(scene, bvh, args.width, args.height, options=render_options, keep_cost=False)
        job.run(progress=bar)
    result = job.result(depth=False, cost=False, counters=counter is not None)
    t = result.timings
    args.out.parent.mkdir(parents=True, exist_ok=True)
    if result.counters is not None:
        _write_counter(result.counters, counter, args.range, args.out)
    elif result.color is not None:
        color = straight_alpha(result.color)  # PNG: straight alpha (Film ▸ Transparent, a holdout's edges)
        image = legend.render_legends(color, render_options, t["heatmap_scale"], legend.overlay_height(bvh))
        save_png(image, args.out, premultiplied=False)
    print(f"{name}: {args.width}x{args.height} on {t['device']} ({t['backend']}: {t['reason']})")
    print(f"trace {t['trace_ms']:.1f} ms, total {t['total_ms']:.1f} ms; {_tree_summary(bvh)}")
    print(f"wrote {args.out}")
    return 0


def _counter(args) -> str | None:
    if args.heatmap and args.counter not in (None, "box_tests"):
        raise ValueError("--heatmap is --counter box_tests: give one of them")
    if args.range is not None and not (args.counter or args.heatmap):
        raise ValueError("--range needs --counter")
    if args.film_transparent and (args.counter or args.heatmap):  # a counter's image has no sky to clear
        raise ValueError("--film-transparent is for the shaded image; a counter's image has no transparency")
    if args.bvh_depth and (args.counter or args.heatmap):  # the counter's image draws no boxes
        raise ValueError("--bvh-depth draws boxes over the shaded image; a counter's image has none")
    return "box_tests" if args.heatmap else args.counter


def histogram_paths(out: Path) -> tuple[Path, Path]:
    """Where `render --counter` writes the histogram beside OUT: OUT.histogram.png and .json."""
    return out.with_suffix(".histogram.png"), out.with_suffix(".histogram.json")


def counter_paths(out: Path) -> tuple[Path, Path, Path]:
    """Every file `render --counter` writes beside OUT: the counts (OUT.npy) and the histogram."""
    return (out.with_suffix(".npy"), *histogram_paths(out))


def _write_counter(all_counters, counter: str | None, value_range, out: Path) -> None:
    """The counter's image with its scale bar (OUT), its values per primary ray (OUT.npy) and
    their histogram over the colour range (histogram_paths: a strip and its numbers)."""
    assert counter is not None  # the render kept counters because one was asked for
    values = counters.counter_plane(all_counters, counter)
    image, (lo, hi) = counters.counter_image(values, value_range)
    raw, strip_png, numbers = counter_paths(out)
    hist = histogram.counter_histogram(values, counter, value_range)
    buffer = io.BytesIO()
    np.save(buffer, values)
    # the four together (an interrupt left the new image and counts beside the old histogram)
    write_together(
        {
            out: png_file_bytes(image),
            raw: buffer.getvalue(),
            strip_png: png_file_bytes(histogram.histogram_strip(hist, values.shape[1])),
            numbers: strict_json.dumps(hist.to_json(), indent=2).encode(),
        }
    )
    how = "auto: 0 to the 99th percentile" if value_range is None else "given"
    p = hist.percentiles
    print(
        f"{counter} per primary ray: mean {hist.mean:.2f}, p50 {p['p50']:g}, p90 {p['p90']:g}, "
        f"p99 {p['p99']:g}, max {p['max']:g}"
    )
    print(f"colour range {lo:g}..{hi:g} ({how}); counts in {raw}; histogram in {strip_png.name}, {numbers.name}")


def _tree_summary(bvh: Bvh | InstancedBvh) -> str:
    s = bvh.stats
    if isinstance(bvh, InstancedBvh):
        build_ms = sum(m.stats["build_ms"] for m in bvh.meshes) + s["tlas_build_ms"]
        placed = f"{s['instances']} instances of {s['meshes']} meshes"
        return f"build {build_ms:.1f} ms, {placed}, TLAS height {s['tlas_height']}"
    return f"build {s['build_ms']:.1f} ms, height {s['height']}"
