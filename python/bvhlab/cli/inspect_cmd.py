"""`bvhlab inspect SCENE --node N | --pixel X,Y | --worst K`: why a tree is good or bad (issue 35).
Prints one node's figures (box, place in the tree, SAH term and share, child overlap, EPO), one
pixel's primary-ray traversal as a table (through the renderer's camera and traversal code; for
a scene with instances, the TLAS's boxes and each instance's walk), or
the K subtrees of largest SAH cost; --json writes the same. For a scene with instances the tree
is the TLAS with each instance's mesh tree in its leaf: --node N is TLAS node N, or node N of
instance I's mesh tree with --instance I, and --worst lists nodes of both levels. The tree is built with the build
options or read from a file saved with --save-tree (or Bvh.save), and optimised with --optimize N."""

from __future__ import annotations

import argparse
import contextlib
import io
import sys
from pathlib import Path

from .. import InstancedBvh, build, load_bvh
from .. import _json as strict_json
from .._atomic import write_together
from .._checks import input_file
from .._progress import ProgressBar, Ticker
from ..inspect.levels import TreeNode
from ..inspect.ray_record import PIXEL_TRAVERSALS, trace_pixel
from ..inspect.tree_file import SUFFIX, TreeFileError, tree_bytes, tree_path
from ..render_options import DEFAULT_HEIGHT, DEFAULT_WIDTH, RenderOptions
from . import options

_DEFAULT = RenderOptions()
#: What --save-tree says of a scene with instances.
TWO_LEVEL_NOT_SAVED = (
    "--save-tree takes a flat scene's tree; this scene has instances (a two-level tree), whose trees "
    "are not saved to a file"
)
#: What --instance says of a flat scene.
FLAT_HAS_NO_INSTANCES = "--instance I names an instance of a scene with instances; this scene is flat"
_NODE_ROWS = (
    "depth",
    "parent",
    "left",
    "right",
    "prim_count",
    "lo",
    "hi",
    "area",
    "sah_term",
    "subtree_sah",
    "sah_share",
    "child_overlap",
    "epo",
)


def add_parser(sub) -> None:
    p = sub.add_parser(
        "inspect", help="a node's figures, a pixel's traversal, the costliest subtrees", description=__doc__
    )
    options.add_scene(p)
    options.add_build(p)
    options.typed_build_options(p)  # with --tree, the ones typed must be the saved tree's
    options.add_optimize(p)
    what = p.add_mutually_exclusive_group(required=True)
    what.add_argument("--node", type=lambda t: options.whole_number(t, 0, 2**32 - 1), metavar="N", help="node index")
    what.add_argument("--pixel", type=pixel_spec, metavar="X,Y", help="pixel (row 0 at the top) of a render")
    what.add_argument("--worst", type=lambda t: options.whole_number(t, 1, 10**6), metavar="K")
    p.add_argument(
        "--instance",
        type=lambda t: options.whole_number(t, 0, 2**32 - 1),
        metavar="I",
        help="(--node, a scene with instances) node N of instance I's mesh tree instead of the TLAS's",
    )
    p.add_argument(
        "--tree",
        type=Path,
        metavar="FILE",
        help=f"read the tree from FILE ({SUFFIX}) instead of building (build options given must be its own)",
    )
    p.add_argument(
        "--save-tree", type=options.output_file_type(SUFFIX, "tree file"), metavar="FILE", help="also save the tree"
    )
    options.add_image_size(p, defaults=False)  # the pixel's options: None unless given (PIXEL_DEFAULTS)
    p.add_argument(
        "--samples-per-axis", type=options.samples_per_axis, metavar="N", help="N×N samples per pixel (--pixel)"
    )
    p.add_argument("--sample", type=lambda t: options.whole_number(t, 0, 2**32 - 1), help="(--pixel)")
    p.add_argument("--traversal", choices=PIXEL_TRAVERSALS, help="(--pixel)")
    p.add_argument("--json", type=options.output_file_type(".json", "inspection file"), metavar="PATH")
    p.set_defaults(run=run)


def pixel_spec(text: str) -> tuple[int, int]:
    """'12,7' → (12, 7)."""
    try:
        x, y = (int(v) for v in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"a pixel must look like X,Y (e.g. 12,7), got '{text}'") from None
    if x < 0 or y < 0:
        raise argparse.ArgumentTypeError(f"pixel {text}: coordinates must be >= 0")
    return x, y


#: The options of --pixel, and their values where not given.
PIXEL_DEFAULTS = {
    "width": DEFAULT_WIDTH,
    "height": DEFAULT_HEIGHT,
    "samples_per_axis": _DEFAULT.samples_per_axis,
    "sample": 0,
    "traversal": _DEFAULT.traversal,
}


def run(args) -> int:
    given = [key for key in PIXEL_DEFAULTS if getattr(args, key) is not None]
    if given and args.pixel is None:  # they were accepted and ignored
        raise ValueError(f"--{given[0].replace('_', '-')} is an option of --pixel X,Y (the render the pixel is of)")
    for key, value in PIXEL_DEFAULTS.items():
        if getattr(args, key) is None:
            setattr(args, key, value)
    if args.pixel is not None and not (args.pixel[0] < args.width and args.pixel[1] < args.height):
        # before any work (the tree was built and saved, then this refused)
        raise ValueError(f"pixel {tuple(args.pixel)} lies outside the {args.width}×{args.height} image")
    typed = options.fill_build_defaults(args)
    settings = options.build_kwargs(args)  # checked before the scene is loaded
    optimize = options.optimize_config(args)
    if args.instance is not None and args.node is None:  # it was ignored, out of range or not
        raise ValueError("--instance I goes with --node N (node N of instance I's mesh tree)")
    # before the scene is loaded and the tree built (each was refused after them: a probe)
    n = args.samples_per_axis * args.samples_per_axis
    if args.pixel is not None and args.sample >= n:
        raise ValueError(
            f"sample {args.sample} does not exist: a pixel has {'one sample' if n == 1 else f'{n} samples'}"
        )
    if args.tree:
        tree_file = Path(args.tree)
        input_file(tree_file, "tree file", TreeFileError)
        if not tree_file.exists():
            raise FileNotFoundError(2, "No such file or directory", str(tree_file))
    scene, name = options.read_scene(args.scene)
    if scene.is_instanced and args.save_tree:
        raise ValueError(TWO_LEVEL_NOT_SAVED)
    if scene.is_instanced and optimize is not None:
        raise ValueError(options.OPTIMIZE_FLAT_ONLY)
    if args.tree:
        bvh = load_bvh(args.tree, scene)
        # build options typed beside --tree must be the saved tree's (they were ignored; those not
        # typed are not compared: a default is no claim about the file)
        for key, value in typed.items():
            if getattr(bvh.config, key) != value:
                raise TreeFileError(f"{args.tree} was built with {key}={getattr(bvh.config, key)}, not {key}={value}")
    else:
        with ProgressBar(f"building {args.method}") as bar:
            bvh = build(scene, progress=bar, **settings)
    options.optimize_tree(bvh, optimize)
    two_level = isinstance(bvh, InstancedBvh)
    if not two_level and args.instance is not None:
        raise ValueError(FLAT_HAS_NO_INSTANCES)
    # before the tree is saved (it was, then refused) and the node figures' EPO pass (39 s of a
    # 15,000-triangle soup)
    _check_node(bvh, args, two_level)
    # the report is printed after its files are written (a reader gone, `| head`, lost the file)
    with contextlib.redirect_stdout(io.StringIO()) as printed:
        report = _report(args, scene, name, bvh, two_level)
    # the tree and the report written together, whole or not at all: the tree was saved before the
    # report was made, so a Ctrl-C there or a report that could not be written had replaced it alone
    files: dict[Path, bytes] = {}
    if args.save_tree:
        files[tree_path(args.save_tree)] = tree_bytes(bvh)
    if args.json:
        files[Path(args.json)] = (strict_json.dumps(report, indent=1) + "\n").encode()
    for path in files:
        path.parent.mkdir(parents=True, exist_ok=True)  # as build --json makes its folder
    write_together(files)
    sys.stdout.write(printed.getvalue())
    for path in files:
        print(f"wrote {path}")
    return 0


def _report(args, scene, name: str, bvh, two_level: bool) -> dict:
    """Prints the tree's line and what was asked (a node, a pixel, the costliest subtrees);
    returns the same as the report --json writes."""
    stats = bvh.stats
    # --pixel needs no node figures (their EPO pass took 17 s of a 15,000-triangle soup's pixel)
    data = _node_data(bvh) if args.pixel is None else None
    if two_level:
        keys = ("instances", "meshes", "tlas_nodes", "tlas_height", "tlas_sah_cost", "nodes", "sah_cost")
        tree = {"method": stats["method"], **{k: stats[k] for k in keys}}
        print(f"{name}: {stats['triangles_flattened']} triangles flattened, stored once per mesh; " + _pairs(tree))
    else:
        tree = {"method": stats["method"], "nodes": stats["nodes"], "height": stats["height"]}
        tree |= {"sah_cost": data.sah_cost, "epo_cost": data.epo_cost} if data else {"sah_cost": stats["sah_cost"]}
        print(f"{name}: {stats['triangles']} triangles, {stats['spheres']} spheres; " + _pairs(tree))
    report: dict = {
        "about": {"scene": name, "source": args.scene, "settings": bvh.config.tree_settings()},
        "tree": tree,
    }
    if args.node is not None and two_level:
        level = TreeNode("tlas", args.node) if args.instance is None else TreeNode("blas", args.node, args.instance)
        report["node"] = _print_two_level_node(data, level)
    elif args.node is not None:
        report["node"] = _print_node(data, args.node)
    elif args.pixel is not None:
        report["pixel"] = _print_pixel(scene, bvh, args)
    elif two_level:
        report["worst"] = _print_two_level_worst(data, args.worst)
    else:
        report["worst"] = _print_worst(data, args.worst)
    return report


def _check_node(bvh, args, two_level: bool) -> None:
    """--node N (and --instance I) name a node the tree has: ValueError saying the range if not."""
    if args.node is None:
        return
    if two_level and args.instance is not None:
        mesh_of, _ = bvh.instances
        if args.instance >= len(mesh_of):
            raise ValueError(f"--instance {args.instance} does not exist: the scene has {len(mesh_of)} instances")
        tree, what = bvh.meshes[int(mesh_of[args.instance])], f"instance {args.instance}'s mesh tree"
        count = len(tree.nodes)
    else:
        count, what = (bvh.stats["tlas_nodes"], "the TLAS") if two_level else (bvh.stats["nodes"], "the tree")
    if args.node >= count:
        nodes = "one node (0)" if count == 1 else f"{count} nodes (0 to {count - 1})" if count else "no nodes"
        raise ValueError(f"--node {args.node} does not exist: {what} has {nodes}")


def _print_node(data, node: int) -> dict:
    figures = data.node(node)
    print(f"node {node} ({'leaf' if figures['leaf'] else 'internal'})")
    for key in _NODE_ROWS:
        print(f"  {key:<14}{_value(figures[key])}")
    return figures


def _print_two_level_node(data, node: TreeNode) -> dict:
    figures = data.figures(node)
    where = "the TLAS" if node.level == "tlas" else f"instance {node.instance}'s mesh tree (mesh {figures['mesh']})"
    print(f"node {node.node} of {where} ({'leaf' if figures['leaf'] else 'internal'})")
    rows = _NODE_ROWS if node.level == "tlas" else ("tlas_leaf", "depth_in_mesh_tree", *_NODE_ROWS)
    for key in rows:
        print(f"  {key:<19}{_value(figures[key])}")
    if node.level == "blas":
        print("  (lo, hi: in the mesh's space; depth, subtree_sah and sah_share: of the whole tree)")
    return figures


def _print_two_level_worst(data, k: int) -> list[dict]:
    rows = []
    costliest = data.costliest(k)
    what = f"the {len(costliest)} subtrees" if len(costliest) != 1 else "the one subtree"
    print(f"{what} of largest SAH cost (share of the whole tree's {data.sah_cost:.4g}):")
    head = ("level", 5), ("instance", 8), ("node", 8), ("depth", 5), ("prims", 9), ("subtree SAH", 12), ("share", 7)
    print("  " + " ".join(f"{name:>{width}}" for name, width in head))
    for node, _ in costliest:
        f = data.figures(node)
        rows.append(f)
        inst = f.get("instance", "")
        print(
            f"  {f['level']:>5} {inst:>8} {f['node']:>8} {f['depth']:>5} {f['prim_count']:>9} "
            f"{f['subtree_sah']:>12.4f} {f['sah_share']:>7.2%}"
        )
    return rows


def _print_pixel(scene, bvh, args) -> dict:
    x, y = args.pixel
    ray_options = RenderOptions(samples_per_axis=args.samples_per_axis, traversal=args.traversal)
    record = trace_pixel(
        scene, bvh, x, y, width=args.width, height=args.height, options=ray_options, sample=args.sample
    )
    summary = record.summary()
    two_level = "instance" in summary
    print(f"pixel {x},{y} sample {args.sample} of a {args.width}×{args.height} render, {args.traversal} traversal:")
    keys: tuple[str, ...] = ("nodes_visited", "box_tests", "box_hits", "prim_tests", "t", "prim", "kind")
    if two_level:
        keys = ("nodes_visited", "tlas_box_tests", "instances_entered", *keys[1:], "instance")
    print("  " + _pairs({k: summary[k] for k in keys}))
    if summary["hit_leaf"] < 0:
        print("  no hit")
    elif two_level:
        print(f"  closest hit in instance {summary['instance']}, leaf {summary['hit_leaf']} of its mesh's tree")
    else:
        print(f"  closest hit in leaf {summary['hit_leaf']}")
    steps = record.steps()
    print(f"  {'#':>5}  {'inst':>5} {'test':<9} {'node':>8} {'slot':>8} {'prim':>10}  result")
    for i, s in enumerate(steps):
        inst = s.get("instance", "")
        if s["step"] in ("box", "tlas box"):
            result = "entered" if s["hit"] else "missed"
            print(f"  {i:>5}  {inst:>5} {s['step']:<9} {s['node']:>8} {'':>8} {'':>10}  {result}")
        elif s["step"] == "wide node":
            print(f"  {i:>5}  {inst:>5} {'wide node':<9} {s['node']:>8} {'':>8} {'':>10}  its children's boxes:")
        elif s["step"] == "instance":
            result = "came closer" if s["closer"] else "-"
            print(f"  {i:>5}  {inst:>5} {'instance':<9} {s['leaf']:>8} {'':>8} {'':>10}  {result}")
        else:
            result = "closest so far" if s["closer"] else "-"
            prim = f"{s['kind'][0]}{s['prim']}"
            print(f"  {i:>5}  {inst:>5} {'prim':<9} {s['leaf']:>8} {s['slot']:>8} {prim:>10}  {result}")
    return {**summary, "steps": steps}


def _print_worst(data, k: int) -> list[dict]:
    rows = []
    worst = data.worst(k)
    what = f"the {len(worst)} subtrees" if len(worst) != 1 else "the one subtree"
    print(f"{what} of largest SAH cost (share of the tree's {data.sah_cost:.4g}):")
    head = ("node", 8), ("depth", 5), ("prims", 8), ("subtree SAH", 12), ("share", 7), ("own term", 10)
    print("  " + " ".join(f"{name:>{width}}" for name, width in (*head, ("overlap", 8), ("EPO", 10))))
    for node in worst:
        f = data.node(int(node))
        rows.append(f)
        print(
            f"  {f['node']:>8} {f['depth']:>5} {f['prim_count']:>8} {f['subtree_sah']:>12.4f} {f['sah_share']:>7.2%} "
            f"{f['sah_term']:>10.4f} {f['child_overlap']:>8.3f} {f['epo']:>10.4g}"
        )
    return rows


def _value(v) -> str:
    if isinstance(v, float):
        return f"{v:.6g}"
    if isinstance(v, list):
        return "(" + ", ".join(_value(c) for c in v) + ")"
    return str(v)


def _pairs(d: dict) -> str:
    return ", ".join(f"{k} {_value(v)}" for k, v in d.items())


def _node_data(bvh):
    """bvh.node_data(), a ticker on the terminal while it runs (its EPO pass took 11 s of a
    15,000-triangle soup with nothing shown: a helper's audit)."""
    with Ticker("node figures (end-point overlap)"):
        return bvh.node_data()
