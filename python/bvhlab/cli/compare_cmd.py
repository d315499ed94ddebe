"""`bvhlab compare SCENE --out DIR`: the report's Table 1 for SCENE (frame time, build time and
tree height per split method, plus SAH cost, nodes, leaves, primary-ray throughput), the
report's claims checked on it, charts, Figures 3–5 per method, and one level sheet per method."""
from __future__ import annotations

import sys
import time
from pathlib import Path

from ..compare import charts, figures
from ..compare import measure_methods, report_checks, write_tables
from ..render import BACKENDS, Renderer
from ..library import bundled_dir, load_scene
from . import options


def add_parser(sub) -> None:
    p = sub.add_parser("compare", help="reproduce the report's Table 1 and figures", description=__doc__)
    options.add_scene(p)
    p.add_argument("--methods", default="median,mean,sah12,sah32",
                   help="comma-separated: median, mean, midpoint, lbvh, sweep_sah, sah<B> (default: the report's)")
    p.add_argument("--frames", type=int, default=5, help="frames averaged per method, after one warm-up")
    p.add_argument("--builds", type=int, default=5, help="builds per method; the median build time is reported")
    p.add_argument("--width", type=int, default=800)
    p.add_argument("--height", type=int, default=600)
    p.add_argument("--backend", default="auto", choices=BACKENDS)
    p.add_argument("--no-figures", action="store_true", help="skip Figures 3-5 and the level sheets")
    p.add_argument("--no-uniform", action="store_true", help="skip the random-spheres check (report §4.2)")
    p.add_argument("--out", type=Path, required=True, help="directory for tables, charts and figures")
    p.set_defaults(run=run)


def say(text: str) -> None:
    print(text, file=sys.stderr, flush=True)


def run(args) -> int:
    labels = [m.strip() for m in args.methods.split(",") if m.strip()]
    for label in labels:
        options.method_kwargs(label)  # unknown names fail before any work
    scene, name = load_scene(args.scene)
    if not scene.primitive_count:
        raise ValueError(f"scene '{name}' has no geometry")
    out = args.out
    out.mkdir(parents=True, exist_ok=True)
    renderer = Renderer(args.backend)
    if renderer.fallback:
        say(renderer.fallback)
    started = time.perf_counter()
    rows = measure_methods(scene, labels, frames=args.frames, builds=args.builds, width=args.width,
                           height=args.height, renderer=renderer, progress=lambda s: say(f"[{name}] {s}"))
    uniform = None
    if not args.no_uniform:
        spheres, _ = load_scene("gen:random_spheres")
        uniform = measure_methods(spheres, labels, frames=max(1, args.frames // 2), builds=1, width=args.width // 2,
                                  height=args.height // 2, renderer=renderer, progress=lambda s: say(f"[random spheres] {s}"))
    checks = report_checks(rows, uniform)
    meta = {"scene": name, "triangles": len(scene.triangles), "spheres": len(scene.spheres), "width": args.width,
            "height": args.height, "frames": args.frames, "builds": args.builds, "device": renderer.device,
            "backend": renderer.backend, "uniform_rows": uniform}
    paths = write_tables(rows, out, meta, checks)
    print(paths["md"].read_text())
    charts.times_chart(rows, out / "times.png", f"{name}: frame and build time per split method")
    charts.nodes_per_depth_chart(rows, out / "nodes_per_depth.png", f"{name}: nodes per depth")
    if not args.no_figures:
        write_figures(labels, out, renderer)
        write_sheets(args.scene, labels, out)
    say(f"compare finished in {time.perf_counter() - started:.0f} s; wrote {out}")
    return 0


def write_figures(labels: list[str], out: Path, renderer: Renderer) -> None:
    bundled = bundled_dir() is not None and _has_bpy()
    spheres, _ = load_scene("five_spheres" if bundled else "gen:five_spheres")
    mesh, mesh_name = load_scene("suzanne_250k" if bundled else "gen:knot")
    for fig, scene in (("figure3", spheres), ("figure4", spheres), ("figure5", mesh)):
        say(f"[figures] {fig}: {figures.FIGURES[fig][0]}")
        figures.render_figure(fig, scene, labels, out, renderer, line_width=2.0)


def write_sheets(scene_spec: str, labels: list[str], out: Path) -> None:
    from ..snapshot import run_sheet

    for label in labels:
        say(f"[sheets] {label}")
        try:
            run_sheet(scene_spec, options.method_kwargs(label), out / f"sheet_{label}.png")
        except RuntimeError as e:  # no OpenGL (EGL) on this machine: say so, keep the rest
            say(f"[sheets] skipped: {e}")
            return


def _has_bpy() -> bool:
    import importlib.util

    return importlib.util.find_spec("bpy") is not None
