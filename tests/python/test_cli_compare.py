"""`bvhlab compare` end to end: the table, charts, figures and sheets it writes, the report's
overlay claim measured, bad arguments refused, nothing written over, and a width of one pixel."""

import csv
import json

import numpy as np
import pytest
from test_cli import line_pixels, run_cli

import bvhlab
from bvhlab.library import load_scene, procedural
from bvhlab.render import HAS_VULKAN


def test_compare_writes_table_charts_figures_and_sheets(tmp_path):
    out = tmp_path / "cmp"
    code, stdout, stderr = run_cli(
        "compare",
        "gen:five_spheres",
        "--methods",
        "median,mean,sah12",
        "--frames",
        "5",
        "--builds",
        "5",
        "--width",
        "64",
        "--height",
        "48",
        "--backend",
        "cpu",
        "--overlay-backends",
        "none",
        "--out",
        out,
    )
    assert code == 0, stderr
    assert "Checks (report §4.2, §5.2)" in stdout and "Report §4.1" not in stdout
    rows = list(csv.DictReader((out / "table.csv").open()))
    assert [r["method"] for r in rows] == ["median", "mean", "sah12"]
    scene, _ = load_scene("gen:five_spheres")
    for row, kwargs in zip(rows, [dict(method="median"), dict(method="mean"), dict(method="sah", bins=12)]):
        stats = bvhlab.build(scene, axis="largest", max_leaf_size=1, **kwargs).stats
        assert int(row["height"]) == stats["height"] and int(row["nodes"]) == stats["nodes"]
        assert float(row["sah_cost"]) == pytest.approx(stats["sah_cost"], rel=1e-3)
        assert float(row["frame_ms"]) > 0 and float(row["build_ms"]) > 0 and float(row["frame_cpu_ms"]) > 0
        assert float(row["frame_cpu_ms_lo"]) <= float(row["frame_cpu_ms"]) <= float(row["frame_cpu_ms_hi"])
    table = json.loads((out / "table.json").read_text())
    assert len(table["checks"]) >= 5
    assert all(c["verdict"] in ("holds", "does NOT hold", "inconclusive") for c in table["checks"])
    assert all(len(r["frame_ms_all"]) == 5 and len(r["build_cpu_ms_all"]) == 5 for r in table["rows"])
    assert len(table["meta"]["uniform_rows"][0]["frame_ms_all"]) == 5  # random spheres: the same protocol
    md = (out / "table.md").read_text()
    assert "| median |" in md and "41.8" in md and "mean (centroid mean" in md
    for name in (
        "times.png",
        "nodes_per_depth.png",
        "sah_per_depth.png",
        "leaf_sizes.png",
        "figure6.png",
        "sheet_median.png",
    ):
        assert (out / name).stat().st_size > 1000, name
    # Figure 3 draws depth 1 only; Figure 4 depths 1 and deeper, never the root
    for method in ("median", "mean", "sah12"):
        assert line_pixels(out / f"figure3_{method}.png", 1) > 20
        assert line_pixels(out / f"figure3_{method}.png", 0) == 0
        assert line_pixels(out / f"figure4_{method}.png", 2) > 0
        assert line_pixels(out / f"figure5_{method}.png", 8) + line_pixels(out / f"figure5_{method}.png", 9) > 0


def test_compare_frames_take_the_walk_asked_for(tmp_path):
    """--traversal stackless: the report's fixed depth-first order (§3.1) rather than the ordered
    stack walk (review: the table did not say which walk its frames took); the table says it."""
    out = tmp_path / "walk"
    code, stdout, stderr = run_cli(
        "compare", "gen:five_spheres", "--methods", "median,sah12", "--frames", "5", "--builds", "5",
        "--width", "16", "--height", "12", "--backend", "cpu", "--overlay-backends", "none",
        "--no-figures", "--no-uniform", "--traversal", "stackless", "--out", out,
    )  # fmt: skip
    assert code == 0, stderr
    table = json.loads((out / "table.json").read_text())
    assert table["meta"]["traversal"] == "stackless"
    assert [r["traversal"] for r in table["rows"]] == ["stackless", "stackless"]
    assert "the stackless walk (the report's fixed depth-first order)" in (out / "table.md").read_text()


def test_compare_measures_the_overlay_claim(tmp_path):
    """Report §4.1 on the >700,000-triangle model, on the CPU reference and on Vulkan."""
    out = tmp_path / "cmp"
    code, stdout, stderr = run_cli(
        "compare",
        "gen:whitted",
        "--methods",
        "sah12",
        "--frames",
        "5",
        "--builds",
        "5",
        "--width",
        "48",
        "--height",
        "36",
        "--backend",
        "cpu",
        "--no-figures",
        "--no-uniform",
        "--overlay-backends",
        "cpu,vulkan",
        "--out",
        out,
    )
    assert code == 0, stderr
    assert "Report §4.1 and Figure 5" in stdout and "| CPU reference on 1 thread | no overlay |" in stdout
    overlay = json.loads((out / "table.json").read_text())["meta"]["overlay"]
    assert {o["backend"] for o in overlay} == ({"cpu", "vulkan"} if HAS_VULKAN else {"cpu"})
    for o in overlay:
        assert o["boxes"] > 0 and len(o["rows"]) == 3
        assert all(r["verdict"] in ("holds", "does NOT hold", "inconclusive") for r in o["rows"][1:])
        png = out / f"figure5_overlay_{o['backend']}.png"
        assert line_pixels(png, 8) + line_pixels(png, 9) > 0


@pytest.mark.parametrize(
    "args, message",
    [
        (["--frames", "0"], "argument --frames: must be at least 5"),
        (["--frames", "-2"], "argument --frames: must be at least 5"),
        (["--frames", "4"], "argument --frames: must be at least 5"),
        (["--frames", "many"], "argument --frames: expected a whole number, got 'many'"),
        (["--builds", "0"], "argument --builds: must be at least 5"),
        (["--methods", ","], "argument --methods: no methods given"),
        (["--methods", "median,,sah12"], "argument --methods: empty method name"),
        (["--methods", "median,median"], "argument --methods: method given more than once: median"),
        (["--methods", "sah,median,sah12"], "argument --methods: sah and sah12 are the same build: give one"),
        (["--methods", "sah012,sah12"], "argument --methods: sah012 and sah12 are the same build"),
        (["--methods", "quick"], "argument --methods: unknown method 'quick'"),
        (["--width", "0"], "argument --width: must be between 1 and 16384 pixels, got 0"),
        (["--height", "100000"], "argument --height: must be between 1 and 16384 pixels, got 100000"),
        (["--overlay-backends", "gpu"], "argument --overlay-backends: expected cpu, vulkan"),
        (["--traversal", "wide"], "argument --traversal: invalid choice: 'wide'"),
    ],
)
def test_compare_rejects_bad_arguments(tmp_path, args, message):
    out = tmp_path / "never"
    code, stdout, stderr = run_cli("compare", "gen:five_spheres", *args, "--out", out, timeout=60)
    assert code == 2 and f"bvhlab compare: error: {message}" in stderr, stderr
    assert "Traceback" not in stderr and not out.exists()


def test_compare_never_writes_over_a_file(tmp_path):
    existing = tmp_path / "result.png"
    existing.write_bytes(b"keep me")
    code, _, stderr = run_cli("compare", "gen:five_spheres", "--out", existing, timeout=60)
    assert code == 2 and "bvhlab compare: error: argument --out:" in stderr and "is not a directory" in stderr
    code, _, stderr = run_cli("compare", "gen:five_spheres", "--out", existing / "sub", timeout=60)
    assert code == 2 and f"{existing} is a file" in stderr
    assert existing.read_bytes() == b"keep me"


def test_compare_at_width_one(tmp_path):
    """The random-spheres check used to halve the size and fail with "got 0"."""
    out = tmp_path / "tiny"
    code, stdout, stderr = run_cli(
        "compare",
        "gen:five_spheres",
        "--methods",
        "median,sah12",
        "--frames",
        "5",
        "--builds",
        "5",
        "--width",
        "1",
        "--height",
        "1",
        "--backend",
        "cpu",
        "--no-figures",
        "--overlay-backends",
        "none",
        "--out",
        out,
    )
    assert code == 0, stderr
    assert "got 0" not in stderr and "1×1" in stdout and "random spheres" in stderr


def test_compare_and_snapshot_take_an_instanced_scene_whose_own_geometry_is_empty(tmp_path):
    """Instances alone (what Blender's linked duplicates export: mesh 0 empty): the snapshot said
    "has no geometry", and compare, which reaches the sheets last, threw the whole measured run
    away for it (helper probe, 2026-12-07)."""
    knot = procedural.torus_knot(400)
    identity = np.eye(4, dtype=np.float32)[:3]
    moved = identity.copy()
    moved[0, 3] = 3.0
    scene = bvhlab.Scene(meshes=[knot], instance_mesh=np.array([1, 1]), instance_transforms=np.stack([identity, moved]))
    assert scene.primitive_count == 0 and scene.has_geometry
    path = tmp_path / "duplicates.npz"
    scene.save(path)
    code, _, stderr = run_cli("snapshot", path, "--out", tmp_path / "snap.png")
    assert code == 0, stderr
    assert (tmp_path / "snap.png").stat().st_size > 1000
    out = tmp_path / "cmp"
    code, _, stderr = run_cli(
        "compare", path, "--methods", "median,sah12", "--frames", "5", "--builds", "5", "--width", "32",
        "--height", "24", "--backend", "cpu", "--no-uniform", "--overlay-backends", "none", "--out", out,
    )  # fmt: skip
    assert code == 0, stderr
    rows = list(csv.DictReader((out / "table.csv").open()))
    assert [r["method"] for r in rows] == ["median", "sah12"]
    assert (out / "sheet_sah12.png").stat().st_size > 1000
    # an instance of an empty mesh alone places nothing
    empty = bvhlab.Scene(meshes=[np.zeros((0, 3, 3), np.float32), knot], instance_mesh=np.array([1]),
                         instance_transforms=identity[None])  # fmt: skip
    assert not empty.has_geometry
