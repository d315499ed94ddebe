"""`bvhlab scenes`: the bundled and generated scenes a SCENE argument can name."""

from __future__ import annotations

from ..library import bundled_dir, list_scenes


def add_parser(sub) -> None:
    p = sub.add_parser("scenes", help="list the scenes SCENE may name", description=__doc__)
    p.set_defaults(run=run)


def run(args) -> int:
    rows = list_scenes()
    width = max(len(s.name) for s in rows)
    for s in rows:
        counts = f"{s.triangles:>9} tris {s.spheres:>6} spheres" if s.triangles >= 0 else " " * 28
        print(f"{s.name:<{width}}  {counts}  {s.description}")
    where = bundled_dir()
    print(f"\nbundled .blend files: {where}" if where else "\nno bundled .blend files found")
    return 0
