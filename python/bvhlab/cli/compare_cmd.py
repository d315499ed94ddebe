"""`bvhlab compare SCENE --out DIR`: the report's Table 1 for SCENE (frame time, build time and
tree height per split method, plus SAH cost, nodes, leaves, primary-ray throughput) measured with
a protocol (warm-up, interleaved rounds, medians with their spread; a verdict only when a
difference exceeds the spread), the report's claims checked on it, its §4.1 overlay claim and
Figure 5 on a model of over 700,000 triangles, charts, Figures 3–6 and one level sheet per method.
With --counter-diff A,B it writes only two trees side by side instead: a traversal counter per
pixel (--counter) of the same view with the trees of methods A and B (side by side on one heat
range), their difference A − B as a diverging image with its legend, the counts, and each one's
mean and percentiles."""

from __future__ import annotations

import sys
import time
from pathlib import Path

from .. import build, counters
from .._atomic import staged_folder
from .._folder_lock import folder_lock
from ..compare import charts, counter_diff, figures, measure_methods, overlay, report_checks, write_tables
from ..compare.measure import REPORT_BUILD, build_settings, render_frame
from ..compare.protocol import DEFAULT_BUILDS, DEFAULT_FRAMES, MAX_SAMPLES, MIN_SAMPLES
from ..library import load_scene
from ..png import save_png
from ..render import BACKENDS, Renderer, VulkanUnavailable
from ..render_options import RenderOptions
from . import compare_args as cargs
from . import options


def add_parser(sub) -> None:
    p = sub.add_parser("compare", help="reproduce the report's Table 1 and figures", description=__doc__)
    options.add_scene(p)
    p.add_argument(
        "--methods",
        type=cargs.method_list,
        default=None,
        help="comma-separated: median, mean, midpoint, lbvh, sweep_sah, sah<B> "
        f"(default: {cargs.DEFAULT_METHODS}, the report's with both readings of 'mean')",
    )
    p.add_argument(
        "--frames",
        type=cargs.sample_count,
        default=None,
        help=f"frames per method after one warm-up, {MIN_SAMPLES} to {MAX_SAMPLES} (default {DEFAULT_FRAMES})",
    )
    p.add_argument(
        "--builds",
        type=cargs.sample_count,
        default=None,
        help=f"builds per method after one warm-up, {MIN_SAMPLES} to {MAX_SAMPLES} (default {DEFAULT_BUILDS})",
    )
    options.add_image_size(p)
    p.add_argument("--backend", default="auto", choices=BACKENDS, help="renderer of Table 1's frame times")
    p.add_argument(
        "--threads",
        type=cargs.thread_count,
        default=None,
        help="CPU reference threads per frame (default 1, like the builds: on a shared machine one "
        "thread's CPU time measures the work, not the neighbours; 0 = every core)",
    )
    p.add_argument(
        "--traversal",
        choices=TABLE1_TRAVERSALS,
        default=None,
        help="the walk of Table 1's frames (default stack: nearer child first, entries beyond the hit "
        "dropped; stackless: the report's fixed depth-first order, by skip links, §3.1)",
    )
    p.add_argument(
        "--overlay-backends",
        type=cargs.backend_list,
        default=None,
        help="backends for the §4.1 overlay measurement (Figure 5), or 'none' (default: cpu,vulkan)",
    )
    p.add_argument("--no-figures", action="store_true", help="skip Figures 3-6 and the level sheets")
    p.add_argument("--no-uniform", action="store_true", help="skip the random-spheres check (report §4.2)")
    p.add_argument(
        "--counter-diff",
        type=cargs.method_pair,
        metavar="A,B",
        help="only the per-pixel difference A − B of a traversal counter between the trees of two methods",
    )
    p.add_argument(
        "--counter",
        choices=counters.COUNTERS,
        default=None,
        help="the counter of --counter-diff (default box_tests)",
    )
    p.add_argument("--out", type=cargs.output_dir, required=True, help="directory for tables, charts and figures")
    p.set_defaults(run=run)


def say(text: str) -> None:
    print(text, file=sys.stderr, flush=True)


#: The walks Table 1's frames may take: the binary tree's (the report's is the fixed depth-first order,
#: which the stackless walk follows; the stack walk orders children by distance).
TABLE1_TRAVERSALS = ("stack", "stackless")

#: The comparison's own options (None: not given) and their defaults; --counter-diff refuses them
#: (they were accepted and ignored).
COMPARISON_DEFAULTS = {
    "methods": cargs.method_list(cargs.DEFAULT_METHODS),
    "frames": DEFAULT_FRAMES,
    "builds": DEFAULT_BUILDS,
    "threads": 1,
    "traversal": "stack",
    "overlay_backends": cargs.backend_list("cpu,vulkan"),
    "no_figures": False,
    "no_uniform": False,
}


def run(args) -> int:
    if args.counter is not None and not args.counter_diff:  # was run as the whole comparison, silently
        raise ValueError("--counter is the counter of --counter-diff A,B; give both")
    given = [key for key in COMPARISON_DEFAULTS if getattr(args, key) is not None and getattr(args, key) is not False]
    if args.counter_diff and given:
        raise ValueError(
            f"--{given[0].replace('_', '-')} is an option of the comparison (Table 1), not of --counter-diff"
        )
    for key, value in COMPARISON_DEFAULTS.items():
        if getattr(args, key) is None:
            setattr(args, key, value)
    args.counter = args.counter or "box_tests"
    scene, name = options.read_scene(args.scene)
    scene = scene.flattened()  # Table 1 compares split methods over the geometry as it stands
    if not scene.primitive_count:
        raise ValueError(f"scene '{name}' has no geometry")
    out = args.out
    if out.exists():
        say(f"writing into the existing directory {out}")
    out.mkdir(parents=True, exist_ok=True)
    with folder_lock(out, "bvhlab compare"):  # a second run into `out` is refused, not mixed in
        if args.counter_diff:
            return _counter_diff(scene, name, args, out)
        return _compare(scene, name, args, out)


def _counter_diff(scene, name: str, args, out: Path) -> int:
    """Two trees side by side: args.counter per pixel, the first method's minus the second's."""
    first, second = args.counter_diff
    renderer = Renderer(args.backend)
    tree_a, tree_b = counter_diff.build_trees(scene, (first, second))
    result = counter_diff.counter_difference(
        scene, tree_a, tree_b, args.counter, args.width, args.height, renderer=renderer, labels=(first, second)
    )
    with staged_folder(out) as stage:  # the four files together, as _compare's
        paths = counter_diff.write_difference(result, stage, f"counter_diff_{args.counter}_{first}_{second}")
    s = result["summary"]
    for label in (first, second, "first_minus_second"):
        v = s[label]
        shown = f"{first} - {second}" if label == "first_minus_second" else label
        print(f"{name} {args.counter} {shown}: mean {v['mean']:.2f}, median {v['median']:g}, p99 {v['p99']:g}")
    print(f"colour span ±{result['span']:g} (auto: the {s['auto_percentile']:g}th percentile of |difference|)")
    # named where they went (`paths` are the staging folder's, gone now)
    say(f"wrote {out / paths['png'].name}, {paths['side_by_side'].name}, {paths['npy'].name}, {paths['json'].name}")
    return 0


def _compare(scene, name: str, args, out: Path) -> int:
    renderer = Renderer(args.backend)
    if renderer.fallback:
        say(renderer.fallback)
    started = time.perf_counter()
    # every file written in a folder of its own, moved into `out` together at the end: a Ctrl-C or
    # an error leaves `out` as it was (an interrupt left the new tables beside the old charts)
    with staged_folder(out) as stage:
        rows = _measure(scene, name, args, renderer)
        uniform = None if args.no_uniform else _uniform_rows(args, renderer)
        overlay_results, overlay_md = _overlay_check(args, stage)
        meta = _meta(args, name, scene, renderer, uniform, overlay_results)
        paths = write_tables(rows, stage, meta, report_checks(rows, uniform), overlay_md)
        table = paths["md"].read_text()
        _write_charts(rows, scene, name, stage)
        if not args.no_figures:
            _figure6(scene, name, renderer, args, stage)
            _write_figures(args.methods, stage, renderer)
            _write_sheets(args.scene, args.methods, stage)
    print(table)
    say(f"compare finished in {time.perf_counter() - started:.0f} s; wrote {out}")
    return 0


def _uniform_rows(args, renderer) -> list[dict]:
    """Report §4.2: spheres uniformly at random in a cube, measured with the same protocol."""
    spheres, _ = load_scene("gen:random_spheres")
    return _measure(spheres, "random spheres", args, renderer)


def _measure(scene, label: str, args, renderer) -> list[dict]:
    """The methods of the command line on one scene, with the command line's protocol settings."""
    return measure_methods(
        scene,
        args.methods,
        frames=args.frames,
        builds=args.builds,
        width=args.width,
        height=args.height,
        renderer=renderer,
        options=RenderOptions(traversal=args.traversal),
        threads=args.threads,
        progress=lambda s: say(f"[{label}] {s}"),
    )


def _meta(args, name, scene, renderer, uniform, overlay_results) -> dict:
    return {
        "scene": name,
        "triangles": len(scene.triangles),
        "spheres": len(scene.spheres),
        "width": args.width,
        "height": args.height,
        "frames": args.frames,
        "builds": args.builds,
        "device": renderer.device,
        "backend": renderer.backend,
        "build_threads": REPORT_BUILD["threads"],
        "render_threads": args.threads if renderer.backend == "cpu" else None,
        "traversal": args.traversal,
        "build_settings": "one primitive per leaf, split axis of largest centroid extent, SAH with the "
        "bins of its label (12 or 32)",
        "uniform_rows": uniform,
        "overlay": [{k: v for k, v in res.items() if k != "images"} for res in overlay_results],
    }


def _overlay_check(args, out: Path) -> tuple[list[dict], str]:
    """Report §4.1 and Figure 5 on each backend asked for (skipping one that is unavailable)."""
    if not args.overlay_backends:
        return [], ""
    scene, model = figures.figure5_scene()
    bvh = build(scene, **{**build_settings("sah12"), "threads": 0})  # the tree does not depend on threads
    results = []
    for backend in args.overlay_backends:
        try:
            renderer = Renderer(backend)
        except VulkanUnavailable as e:
            say(f"[§4.1] {backend} skipped: {e}")
            continue
        res = overlay.measure_overlay(
            scene,
            bvh,
            renderer,
            frames=args.frames,
            width=args.width,
            height=args.height,
            threads=args.threads,
            progress=lambda s: say(f"[§4.1 {model}] {s}"),
        )
        widest = res["rows"][-1]["setting"]  # the report's screenshots: line width doubled
        save_png(res["images"][widest], out / f"figure5_overlay_{backend}.png")
        results.append(res)
    return results, overlay.markdown(results, model, len(scene.triangles), "SAH 12 bins", bvh.stats["height"])


def _write_charts(rows: list[dict], scene, name: str, out: Path) -> None:
    charts.times_chart(rows, out / "times.png", f"{name}: frame and build time per split method (median, interval)")
    charts.nodes_per_depth_chart(rows, out / "nodes_per_depth.png", f"{name}: nodes per depth")
    charts.sah_per_depth_chart(rows, out / "sah_per_depth.png", f"{name}: SAH cost per depth")
    # §5.1: what SAH leaf termination (dropped by the report) would make of the leaves
    terminated = build(scene, **{**build_settings("sah12", {"max_leaf_size": 8}), "threads": 0})
    extra = {"method": "sah12, leaves ≤ 8 (§5.1)", "leaf_size_histogram": terminated.stats["leaf_size_histogram"]}
    charts.leaf_size_chart([*rows, extra], out / "leaf_sizes.png", f"{name}: leaf sizes")


def _figure6(scene, name: str, renderer: Renderer, args, out: Path) -> None:
    """The report's Figure 6: the Table 1 scene itself, rendered at the table's size (SAH 12)."""
    bvh = build(scene, **{**build_settings("sah12"), "threads": 0})
    image, ms, _, _ = render_frame(renderer, scene, bvh, args.width, args.height, threads=args.threads)
    save_png(image, out / "figure6.png")
    say(f"[figures] figure6: {name} at {args.width}×{args.height}, {ms:.0f} ms")


def _write_figures(labels: list[str], out: Path, renderer: Renderer) -> None:
    spheres, _ = figures.five_spheres_scene()
    mesh, _ = figures.figure5_scene()
    for fig, scene in (("figure3", spheres), ("figure4", spheres), ("figure5", mesh)):
        say(f"[figures] {fig}: {figures.FIGURES[fig][0]}")
        figures.render_figure(fig, scene, labels, out, renderer, line_width=2.0)


def _write_sheets(scene_spec: str, labels: list[str], out: Path) -> None:
    from ..snapshot import run_sheet

    for label in labels:
        say(f"[sheets] {label}")
        try:
            run_sheet(scene_spec, {**build_settings(label), "threads": 0}, out / f"sheet_{label}.png")
        except (RuntimeError, ValueError) as e:
            # no OpenGL (EGL) on this machine, or a scene the sheet does not draw: said, and the
            # measured run kept (a sheet's refusal after the figures threw the whole run away)
            say(f"[sheets] skipped: {e}")
            return
