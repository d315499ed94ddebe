"""`bvhlab build SCENE`: build one tree (a two-level tree for a scene with instances), optimise it
if asked (--optimize N: a flat scene's tree), and print its stats (optionally as JSON)."""

from __future__ import annotations

import dataclasses

from .. import InstancedBvh, build
from .._progress import ProgressBar
from ..stats_files import write_stats
from . import options


def add_parser(sub) -> None:
    p = sub.add_parser("build", help="build a BVH and print its stats", description=__doc__)
    options.add_scene(p)
    options.add_build(p)
    options.add_optimize(p)
    p.add_argument(
        "--json",
        type=options.output_file_type(".json", "stats file"),
        metavar="PATH",
        help='also write the stats to this JSON file ({"about": ..., "stats": ...}, as the add-on\'s Export stats)',
    )
    p.add_argument(
        "--csv",
        type=options.output_file_type(".csv", "stats file"),
        metavar="PATH",
        help="also write the stats to this CSV file (metric,index,value; a value the JSON has as null is empty)",
    )
    p.set_defaults(run=run)


def run(args) -> int:
    settings = options.build_kwargs(args)  # checked before the scene is loaded
    optimize = options.optimize_config(args)
    scene, name = options.read_scene(args.scene)
    if optimize is not None and scene.is_instanced:  # refused before the build
        raise ValueError(options.OPTIMIZE_FLAT_ONLY)
    with ProgressBar(f"building {args.method}") as bar:
        bvh = build(scene, progress=bar, **settings)
    optimized = options.optimize_tree(bvh, optimize)
    stats = bvh.stats
    about = {"scene": name, "source": args.scene, "settings": settings}
    if optimize is not None and optimized is not None:
        about["optimize"] = {**dataclasses.asdict(optimize), "stats": dataclasses.asdict(optimized)}
    write_stats(stats, about, args.json, args.csv)  # before the printout: a reader gone lost them
    if isinstance(bvh, InstancedBvh):
        _print_instanced(name, bvh)
    else:
        _print_flat(name, stats)
    if optimize is not None and optimized is not None:
        print(
            f"  optimized     SAH {optimized.sah_before:.3f} -> {optimized.sah_after:.3f} in {optimized.ms:.0f} ms, "
            f"{optimized.iterations} batches, {optimized.reinsertions} reinsertions ({optimized.stop})"
        )
    for written in (args.json, args.csv):
        if written:
            print(f"wrote {written}")
    return 0


def _print_flat(name: str, stats: dict) -> None:
    print(f"{name}: {stats['triangles']} triangles, {stats['spheres']} spheres")
    for key in (
        "method",
        "bins",
        "axis",
        "nodes",
        "leaves",
        "height",
        "sah_cost",
        "build_ms",
        "avg_leaf_size",
        "max_leaf_size",
        "sah_block",
        "memory_bytes",
    ):
        value = stats[key]
        if value is None:  # bins of a method that does not bin: no line (it printed "None")
            continue
        print(f"  {key:<14}{value:.3f}" if isinstance(value, float) else f"  {key:<14}{value}")
    print(f"  {'nodes/depth':<14}{' '.join(str(n) for n in stats['nodes_per_depth'])}")


def _print_instanced(name: str, bvh: InstancedBvh) -> None:
    """A two-level tree (issue 34): the TLAS, then one line per mesh's tree."""
    stats = bvh.stats
    print(f"{name}: {stats['instances']} instances of {stats['meshes']} meshes")
    width = max(map(len, stats)) + 2  # the longest name (primitives_flattened ran into its value)
    for key, value in stats.items():
        print(f"  {key:<{width}}{value:.3f}" if isinstance(value, float) else f"  {key:<{width}}{value}")
    for k, mesh in enumerate(bvh.meshes):
        m = mesh.stats
        print(f"  mesh {k}: {m['primitives']} primitives, {m['nodes']} nodes, SAH {m['sah_cost']:.3f}")
