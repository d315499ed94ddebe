"""`bvhlab render SCENE --out PNG`: build a tree and render the scene with the Whitted tracer,
optionally with the BVH overlay (--bvh-depth A:B) or as a heatmap of box tests (--heatmap)."""

from __future__ import annotations

from .. import Bvh, InstancedBvh, build, render, save_png
from .._progress import ProgressBar
from ..library import load_scene
from ..render import BACKENDS, TRAVERSALS
from ..render_options import RenderOptions
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
        type=int,
        default=_DEFAULT.max_depth,
        help=f"bounces of reflection and refraction (default {_DEFAULT.max_depth})",
    )
    p.add_argument("--bvh-depth", type=options.depth_range, metavar="A:B", help="draw the boxes of depths A..B")
    p.add_argument("--heatmap", action="store_true", help="colour pixels by the box tests of their primary ray")
    p.add_argument("--traversal", default=_DEFAULT.traversal, choices=TRAVERSALS)
    options.add_png_out(p)
    p.set_defaults(run=run)


def run(args) -> int:
    settings = options.build_kwargs(args)  # checked before the scene is loaded
    render_options = RenderOptions(  # likewise
        samples_per_axis=args.samples_per_axis,
        max_depth=args.max_depth,
        overlay_depth=args.bvh_depth,
        traversal=args.traversal,
        mode="heatmap" if args.heatmap else "shade",
    )
    scene, name = load_scene(args.scene)
    with ProgressBar(f"building {args.method}") as bar:
        bvh = build(scene, progress=bar, **settings)  # an instanced scene: a two-level tree, rendered as it is
    with ProgressBar("rendering") as bar:
        image, t = render(
            scene,
            bvh,
            args.width,
            args.height,
            backend=args.backend,
            options=render_options,
            progress=bar,
        )
    args.out.parent.mkdir(parents=True, exist_ok=True)
    save_png(image, args.out)
    print(f"{name}: {args.width}x{args.height} on {t['device']} ({t['backend']}: {t['reason']})")
    print(f"trace {t['trace_ms']:.1f} ms, total {t['total_ms']:.1f} ms; {_tree_summary(bvh)}")
    print(f"wrote {args.out}")
    return 0


def _tree_summary(bvh: Bvh | InstancedBvh) -> str:
    s = bvh.stats
    if isinstance(bvh, InstancedBvh):
        build_ms = sum(m.stats["build_ms"] for m in bvh.meshes) + s["tlas_build_ms"]
        placed = f"{s['instances']} instances of {s['meshes']} meshes"
        return f"build {build_ms:.1f} ms, {placed}, TLAS height {s['tlas_height']}"
    return f"build {s['build_ms']:.1f} ms, height {s['height']}"
