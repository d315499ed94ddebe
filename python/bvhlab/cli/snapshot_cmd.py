"""`bvhlab snapshot SCENE --out PNG`: a raster preview rendered with moderngl (EGL, headless, in its
own process): the triangles flat-shaded, the spheres drawn, and the boxes of --bvh-depth A:B as
lines coloured by depth. With --sheet: one panel per depth (0 … height) in a grid — how the tree
cuts the model level by level, in a fraction of a traced frame."""

from __future__ import annotations

from . import options


def add_parser(sub) -> None:
    p = sub.add_parser("snapshot", help="raster preview with BVH boxes (moderngl)", description=__doc__)
    options.add_scene(p)
    options.add_build(p)
    what = p.add_mutually_exclusive_group()  # a sheet draws every depth: a range would be ignored
    what.add_argument("--bvh-depth", type=options.depth_range, metavar="A:B", default=None)
    what.add_argument("--sheet", action="store_true", help="one panel per depth, 0 … height, in a grid")
    options.add_image_size(p)
    options.add_png_out(p)
    p.set_defaults(run=run)


def run(args) -> int:
    from ..snapshot import run_sheet, run_snapshot

    kwargs = options.build_kwargs(args)
    if args.sheet:
        run_sheet(args.scene, kwargs, args.out)
    else:
        run_snapshot(args.scene, kwargs, args.out, args.bvh_depth or (0, 0), args.width, args.height)
    print(f"wrote {args.out}")
    return 0
