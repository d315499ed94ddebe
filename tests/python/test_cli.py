"""The bvhlab command line end to end: each subcommand, exit codes, files written and parseable,
and numbers equal to the Python API's for the same builds."""
import csv
import json
import subprocess
import sys

import numpy as np
import pytest

import bvhlab
from bvhlab.cli import main
from bvhlab.png import linear_to_srgb, read_png
from bvhlab.library import load_scene


def run_cli(*args, timeout=300):
    """The CLI in a child process (it may load .blend files through bpy, which changes global state)."""
    done = subprocess.run([sys.executable, "-m", "bvhlab", *map(str, args)], capture_output=True, text=True,
                          timeout=timeout)
    return done.returncode, done.stdout, done.stderr


def test_help_and_scenes(capsys):
    code, out, _ = run_cli("--help")
    assert code == 0 and "compare" in out and "snapshot" in out
    assert main(["scenes"]) == 0
    listed = capsys.readouterr().out
    assert "gen:five_spheres" in listed and "atrium" in listed


def test_build_json_equals_the_api(tmp_path, capsys):
    path = tmp_path / "stats.json"
    assert main(["build", "gen:whitted", "--method", "sah32", "--max-leaf-size", "2", "--json", str(path)]) == 0
    stats = json.loads(path.read_text())
    scene, _ = load_scene("gen:whitted")
    api = bvhlab.build(scene, method="sah", bins=32, max_leaf_size=2).stats
    for key in ("nodes", "leaves", "height", "sah_cost", "nodes_per_depth", "bins", "method"):
        assert stats[key] == api[key], key
    assert "nodes/depth" in capsys.readouterr().out


def line_pixels(png_path, depth: int) -> int:
    """Pixels showing the overlay colour of `depth` (as written to the sRGB PNG)."""
    image = read_png(png_path)[..., :3].astype(int)
    colour = (linear_to_srgb(bvhlab._core.depth_colors(np.array([depth], np.uint32))[0]) * 255 + 0.5).astype(int)
    return int(np.all(np.abs(image - colour) <= 1, -1).sum())


def test_render_with_overlay_and_heatmap(tmp_path):
    out = tmp_path / "render.png"
    assert main(["render", "gen:five_spheres", "--width", "96", "--height", "64", "--backend", "cpu",
                 "--method", "median", "--bvh-depth", "1:1", "--out", str(out)]) == 0
    assert read_png(out).shape == (64, 96, 4)
    assert line_pixels(out, 1) > 20 and line_pixels(out, 2) == 0
    heat = tmp_path / "heat.png"
    assert main(["render", "gen:five_spheres", "--width", "32", "--height", "24", "--backend", "cpu",
                 "--heatmap", "--out", str(heat)]) == 0
    assert read_png(heat).shape == (24, 32, 4)


def test_errors_have_exit_code_2(tmp_path, capsys):
    assert main(["build", str(tmp_path / "missing.npz")]) == 2
    assert "no scene file" in capsys.readouterr().err
    assert main(["build", "gen:whitted", "--method", "quick"]) == 2
    assert "unknown method 'quick'" in capsys.readouterr().err
    assert main(["build", "no-such-scene"]) == 2
    assert "gen:whitted" in capsys.readouterr().err  # the message lists the names
    empty = tmp_path / "empty.npz"
    bvhlab.Scene(camera=bvhlab.Camera((0, -5, 1), (0, 0, 0))).save(empty)
    assert main(["compare", str(empty), "--out", str(tmp_path / "c")]) == 2
    assert "no geometry" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        main(["render", "gen:whitted", "--bvh-depth", "9:2", "--out", str(tmp_path / "x.png")])


def test_compare_writes_table_charts_figures_and_sheets(tmp_path):
    out = tmp_path / "cmp"
    code, stdout, stderr = run_cli("compare", "gen:five_spheres", "--methods", "median,mean,sah12", "--frames", "1",
                                   "--builds", "1", "--width", "64", "--height", "48", "--backend", "cpu",
                                   "--out", out)
    assert code == 0, stderr
    assert "Checks (report §4.2, §5.2)" in stdout
    rows = list(csv.DictReader((out / "table.csv").open()))
    assert [r["method"] for r in rows] == ["median", "mean", "sah12"]
    scene, _ = load_scene("gen:five_spheres")
    for row, kwargs in zip(rows, [dict(method="median"), dict(method="mean"), dict(method="sah", bins=12)]):
        stats = bvhlab.build(scene, **kwargs).stats
        assert int(row["height"]) == stats["height"] and int(row["nodes"]) == stats["nodes"]
        assert float(row["sah_cost"]) == pytest.approx(stats["sah_cost"], rel=1e-3)
        assert float(row["frame_ms"]) > 0 and float(row["build_ms"]) > 0
    table = json.loads((out / "table.json").read_text())
    assert len(table["checks"]) >= 3 and all(isinstance(c["holds"], bool) for c in table["checks"])
    assert "| median |" in (out / "table.md").read_text() and "41.8" in (out / "table.md").read_text()
    for name in ("times.png", "nodes_per_depth.png", "sheet_median.png"):
        assert (out / name).stat().st_size > 1000
    # Figure 3 draws depth 1 only; Figure 4 depths 1 and deeper, never the root
    for method in ("median", "mean", "sah12"):
        assert line_pixels(out / f"figure3_{method}.png", 1) > 20
        assert line_pixels(out / f"figure3_{method}.png", 0) == 0
        assert line_pixels(out / f"figure4_{method}.png", 2) > 0
        assert line_pixels(out / f"figure5_{method}.png", 8) + line_pixels(out / f"figure5_{method}.png", 9) > 0
