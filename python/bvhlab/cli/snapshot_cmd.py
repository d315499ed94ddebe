"""`bvhlab snapshot SCENE --out PNG`: a raster preview rendered with moderngl (EGL, headless, in its
own process): the triangles flat-shaded, the spheres drawn, and the boxes of --bvh-depth A:B as
lines coloured by depth. With --sheet: one panel per depth (0 … height) in a grid — how the tree
cuts the model level by level, in a fraction of a traced frame; --width and --height are then a
panel's (320 × 240 by default)."""

from __future__ import annotations

from . import options


def add_parser(sub) -> None:
    p = sub.add_parser("snapshot", help="raster preview with BVH boxes (moderngl)", description=__doc__)
    options.add_scene(p)
    options.add_build(p)
    what = p.add_mutually_exclusive_group()  # a sheet draws every depth: a range would be ignored
    what.add_argument("--bvh-depth", type=options.depth_range, metavar="A:B", default=None)
    what.add_argument("--sheet", action="store_true", help="one panel per depth, 0 … height, in a grid")
    options.add_image_size(p, defaults=False)  # the image's, or with --sheet a panel's
    options.add_png_out(p)
    p.set_defaults(run=run)


def run(args) -> int:
    from ..snapshot import SHEET_PANEL, run_sheet, run_snapshot

    kwargs = options.build_kwargs(args)
    if args.sheet:  # the panel's size (it was ignored)
        run_sheet(args.scene, kwargs, args.out, args.width or SHEET_PANEL[0], args.height or SHEET_PANEL[1])
    else:
        width, height = args.width or options.DEFAULT_WIDTH, args.height or options.DEFAULT_HEIGHT
        run_snapshot(args.scene, kwargs, args.out, args.bvh_depth or (0, 0), width, height)
    print(f"wrote {args.out}")
    return 0
