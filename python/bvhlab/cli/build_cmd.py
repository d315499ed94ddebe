"""`bvhlab build SCENE`: build one tree and print its stats (optionally as JSON)."""
from __future__ import annotations

import json
from pathlib import Path

from .. import build
from .._progress import ProgressBar
from ..library import load_scene
from . import options


def add_parser(sub) -> None:
    p = sub.add_parser("build", help="build a BVH and print its stats", description=__doc__)
    options.add_scene(p)
    options.add_build(p)
    p.add_argument("--json", type=Path, help="also write the stats to this JSON file")
    p.set_defaults(run=run)


def run(args) -> int:
    scene, name = load_scene(args.scene)
    with ProgressBar(f"building {args.method}") as bar:
        bvh = build(scene, progress=bar, **options.build_kwargs(args))
    stats = bvh.stats
    print(f"{name}: {stats['triangles']} triangles, {stats['spheres']} spheres")
    for key in ("method", "bins", "axis", "nodes", "leaves", "height", "sah_cost", "build_ms", "avg_leaf_size",
                "max_leaf_size", "memory_bytes"):
        value = stats[key]
        print(f"  {key:<14}{value:.3f}" if isinstance(value, float) else f"  {key:<14}{value}")
    print(f"  {'nodes/depth':<14}{' '.join(str(n) for n in stats['nodes_per_depth'])}")
    if args.json:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps({"scene": name, **stats}, indent=1))
        print(f"wrote {args.json}")
    return 0
