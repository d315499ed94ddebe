"""bench/render.py end to end on a small scene (it had stopped running when measure_methods took a
RenderOptions, and nothing ran it): every method, backend and traversal measured, the bounded-
dispatch table filled, the results where --json says and not in bench/results."""

import json
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def test_render_bench_measures_every_method_backend_and_traversal(tmp_path):
    out = tmp_path / "render.json"
    before = (ROOT / "bench/results/render.json").read_bytes()
    run = subprocess.run(
        [sys.executable, "bench/render.py", "--scene", "gen:whitted", "--width", "32", "--height", "24"]
        + ["--frames", "1", "--json", str(out)],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert run.returncode == 0, run.stderr[-2000:]
    assert (ROOT / "bench/results/render.json").read_bytes() == before
    results = json.loads(out.read_text())
    assert (results["width"], results["height"], results["scene"]) == (32, 24, "whitted")
    cells = {(r["method"], r["backend"], r["traversal"]) for r in results["rows"]}
    methods = {"median", "mean", "sah12", "sah32"}
    walks = {"vulkan": ("stack", "stackless"), "cpu": ("stack", "stackless", "wide")}  # wide: the CPU tracer's
    assert cells == {(m, b, t) for m in methods for b, ts in walks.items() for t in ts}
    assert all(r["frame_ms"] > 0 and r["sah_cost"] > 0 for r in results["rows"])
    budgets = results["budgets"]
    assert len(budgets) == 5 and all(b["vulkan_ms"] > 0 and b["cpu_ms"] > 0 for b in budgets)
    assert "frame ms at 32x24" in run.stdout


def test_render_glass_bench_counts_the_shadow_rays_of_each_walk(tmp_path):
    """bench/render_glass.py end to end on whitted (glass already: no variant made), and its glass
    variant of a scene without: the material of fewest triangles made transparent."""
    out = tmp_path / "glass.json"
    run = subprocess.run(
        [sys.executable, "bench/render_glass.py", "--scenes", "gen:whitted", "--size", "48x32", "--rounds", "1"]
        + ["--json", str(out)],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert run.returncode == 0, run.stderr[-2000:]
    (whitted,) = json.loads(out.read_text())["scenes"]
    (stack,), (wide,) = whitted["runs"]["stack"], whitted["runs"]["wide"]
    assert stack["shadow_rays_opaque"] == stack["shadow_rays_glass"] == 0
    assert wide["shadow_rays_opaque"] > 0 and wide["shadow_rays_glass"] > 0 and wide["trace_ms"] > 0

    sys.path.insert(0, str(ROOT / "bench"))
    import dataclasses

    import render_glass

    from bvhlab.library import showcase

    floor, cells = showcase.checker_floor(4, 2.0)  # 32 triangles: 2 of material 2, the rest of 0
    cells[:] = 0
    cells[:2] = 2
    scene = dataclasses.replace(showcase.five_spheres(), triangles=floor, tri_material=cells)
    glassy, k = render_glass.with_glass(scene, None)
    assert k == 2 and glassy.materials[2].transparent > 0 and scene.materials[2].transparent == 0
    assert render_glass.with_glass(glassy, None) is None  # glass already
