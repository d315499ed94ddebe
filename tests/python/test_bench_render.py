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
