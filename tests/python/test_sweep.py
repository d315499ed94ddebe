"""`bvhlab sweep` (issue 37): the spec, the cells' keys, resuming, error rows, Ctrl-C, and the same
table from a two-worker Dask LocalCluster as from the in-process run."""

import itertools
import json
import os
import re
import signal
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq
import pytest
import trimesh
from child import default_sigint

from bvhlab import BuildConfig, build, cli
from bvhlab.library import load_scene
from bvhlab.sweep import local_cluster, plan_cells, read_spec, run_sweep
from bvhlab.sweep.plot import pareto_front
from bvhlab.sweep.summary import RATIO_PLOT, SUMMARY
from bvhlab.sweep.table import CSV, PARQUET
from bvhlab.sweep.task import VARYING, fixed_rays


def _write_spec(folder, scenes, grid="method = ['median', 'sah']\nmax_leaf_size = [1, 4]", rays=2000):
    path = folder / "spec.toml"
    path.write_text(f"scenes = {json.dumps(scenes)}\n[grid]\n{grid}\n[rays]\ncount = {rays}\n")
    return path


@pytest.fixture
def models(tmp_path):
    """Two small mesh files and a hostile one (a NaN vertex), beside the spec."""
    trimesh.creation.icosphere(subdivisions=2).export(tmp_path / "ball.ply")
    trimesh.creation.box(extents=(1, 2, 3)).export(tmp_path / "box.obj")
    (tmp_path / "nan.obj").write_text("v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n")
    return tmp_path


def test_spec_grid_is_every_combination(tmp_path, models):
    spec = read_spec(_write_spec(tmp_path, ["*.ply", "box.obj", "gen:five_spheres"], "method = ['median', 'sah']\n"
                                 "max_leaf_size = [1, 4]\ntraversal = ['wide', 'stack']"))  # fmt: skip
    assert [s.rsplit("/", 1)[-1] for s in spec.scenes] == ["ball.ply", "box.obj", "gen:five_spheres"]
    got = {(s.config.method, s.config.max_leaf_size, s.traversal) for s in spec.settings}
    assert got == set(itertools.product(["median", "sah"], [1, 4], ["wide", "stack"]))
    assert len(plan_cells(spec)) == 3 * 8


@pytest.mark.parametrize(
    "grid, message",
    [
        ("method = 'nope'", "method"),
        ("max_leaf_size = 0", "max_leaf_size"),
        ("colour = 'red'", "unknown key"),
        ("traversal = 'sideways'", "traversal"),
        ("bins = []", "empty list"),
        ("[rays]\nrepeats = 0", "repeats"),
        ("[rays]\ncount = true", "count"),
        ("method = 'sah'\n[report]\nbaseline = 'median'", "baseline 'median' is not a method of the grid"),
        ("method = ['median', 'sah32']\n[report]\nbaseline = 'sah32'", r"the baseline is a method, 'sah'"),
        ("[report]\ncolour = 'red'", "unknown key"),
        # a seed past int64: every cell ran, then writing the table failed (OverflowError), every rerun
        ("seed = 9223372036854775808", "seed must be at most"),
        ("[rays]\nseed = 9223372036854775808", "seed must be a whole number from 0"),
        # float32 held it as 0, and the cells were built with sbvh_alpha 0
        ("method = 'sbvh'\nsbvh_alpha = 1e-46", r"\[grid\] sbvh_alpha must be 0 or of magnitude .*got 1e-46"),
    ],
)
def test_bad_grid_is_refused_naming_the_setting(tmp_path, grid, message):
    path = tmp_path / "spec.toml"
    path.write_text(f"scenes = ['gen:five_spheres']\n[grid]\n{grid}\n")
    with pytest.raises(ValueError, match=message):
        read_spec(path)


def test_glob_matching_nothing_is_refused(tmp_path):
    with pytest.raises(ValueError, match="matches no file"):
        read_spec(_write_spec(tmp_path, ["*.stl"]))


def test_glob_takes_the_scene_files_it_matches(tmp_path, models):
    """The probe's case: "models/*" beside a readme made a cell "FileNotFoundError: no scene" of
    the readme; a glob matching only files that are not scenes is refused as such."""
    (tmp_path / "readme.txt").write_text("the models")
    (tmp_path / "Ball.PLY").write_bytes((tmp_path / "ball.ply").read_bytes())
    spec = read_spec(_write_spec(tmp_path, ["*"]))
    assert [s.rsplit("/", 1)[-1] for s in spec.scenes] == ["Ball.PLY", "ball.ply", "box.obj", "nan.obj"]
    with pytest.raises(ValueError, match=r"'\*\.txt' matches no scene file \(of 1 files\)"):
        read_spec(_write_spec(tmp_path, ["*.txt"]))


def test_globs_read_under_the_spec_folder_whatever_its_name(tmp_path):
    """An audit's cases: a spec in "exp[2]" swept exp2's models (its folder's name read as a
    pattern); "scan[1].obj", a file, was read as the glob matching scan1.obj; a folder a glob
    matched ("parts.obj") became a failed cell."""
    own, other = tmp_path / "exp[2]", tmp_path / "exp2"
    for folder in (own / "models", other / "models"):
        folder.mkdir(parents=True)
    trimesh.creation.box().export(own / "models" / "mine.obj")
    trimesh.creation.box().export(other / "models" / "other.obj")
    (own / "models" / "parts.obj").mkdir()
    trimesh.creation.box().export(own / "scan[1].obj")
    trimesh.creation.box().export(own / "scan1.obj")
    spec = read_spec(_write_spec(own, ["models/*.obj", "scan[1].obj"]))
    assert spec.scenes == (str(own.resolve() / "models" / "mine.obj"), str(own.resolve() / "scan[1].obj"))
    assert read_spec(_write_spec(own, ["scan[0-9].obj"])).scenes == (str(own.resolve() / "scan1.obj"),)
    with pytest.raises(ValueError, match="matches no file"):  # no file of so long a name: an OSError was raised
        read_spec(_write_spec(own, ["x" * 5000 + "*.obj"]))
    # a name that is not UTF-8 is refused before any cell runs (every cell ran, then the table failed)
    trimesh.creation.box().export(os.fsdecode(bytes(own / "models") + b"/m\xff.obj"))
    with pytest.raises(ValueError, match=r"m\\xff\.obj' is not UTF-8: rename it"):
        read_spec(_write_spec(own, ["models/*.obj"]))


def test_grid_methods_are_read_as_the_cli_reads_them(tmp_path):
    """`method = 'sah12'` was refused in a spec, where `--method sah12` builds method sah with 12 bins."""
    spec = read_spec(_write_spec(tmp_path, ["gen:five_spheres"], "method = ['median', 'sah20']"))
    assert {(s.config.method, s.config.bins) for s in spec.settings} == {("median", BuildConfig().bins), ("sah", 20)}
    with pytest.raises(ValueError, match="gives the bins; give bins or sah<B>, not both"):
        read_spec(_write_spec(tmp_path, ["gen:five_spheres"], "method = 'sah12'\nbins = [8, 16]"))


def test_key_changes_with_the_content_and_the_settings(tmp_path, models):
    spec = read_spec(_write_spec(tmp_path, ["box.obj"]))
    keys = [c.key for c in plan_cells(spec)]
    assert len(set(keys)) == len(keys) == 4
    assert keys == [c.key for c in plan_cells(spec)]  # stable
    trimesh.creation.box(extents=(1, 2, 4)).export(models / "box.obj")
    assert not set(keys) & {c.key for c in plan_cells(spec)}


def test_equal_settings_written_differently_have_one_key(tmp_path, models):
    # a float setting written as a whole number: the keys differed, and a rerun measured its cells again
    keys = [
        [c.key for c in plan_cells(read_spec(_write_spec(tmp_path, ["box.obj"], grid)))]
        for grid in ("method = ['sbvh']\nsbvh_alpha = [1]", "method = ['sbvh']\nsbvh_alpha = [1.0]")
    ]
    assert keys[0] == keys[1]
    assert BuildConfig(sbvh_alpha=1).tree_settings() == BuildConfig(sbvh_alpha=1.0).tree_settings()
    assert type(BuildConfig(bins=np.int64(12)).bins) is int
    # the float settings as the core holds them: the default sbvh_alpha is float32(3e-4), which 3e-4
    # typed did not equal (a tree file saved with the default was refused with it)
    assert BuildConfig(method="sbvh") == BuildConfig(method="sbvh", sbvh_alpha=3e-4)
    # as their shortest decimals, not float32's digits (9.999999747378752e-06 showed in labels)
    assert BuildConfig(sbvh_alpha=1e-5).sbvh_alpha == 1e-5 and BuildConfig().sbvh_alpha == 3e-4


def test_in_process_sweep_rows_match_an_independent_build(tmp_path, models):
    spec = read_spec(_write_spec(tmp_path, ["box.obj", "gen:five_spheres"]))
    result = run_sweep(spec, tmp_path / "out", plot=False)
    assert result.ran == len(result.rows) == 8 and result.failed == 0
    for row in result.rows:
        scene, _ = load_scene(row["source"])
        bvh = build(scene, method=row["method"], max_leaf_size=row["max_leaf_size"])
        assert (row["nodes"], row["height"]) == (bvh.stats["nodes"], bvh.stats["height"])
        assert row["sah_cost"] == pytest.approx(bvh.stats["sah_cost"])
        origins, directions = fixed_rays(scene, row["rays"], row["ray_seed"])
        brute = bvh.intersect(origins, directions, traversal="stack")  # another traversal
        assert row["hits"] == int(np.isfinite(brute["t"]).sum()) > 0
        assert row["mrays_per_s"] > 0
    table = pq.read_table(tmp_path / "out" / PARQUET).to_pylist()
    assert [r["key"] for r in table] == [r["key"] for r in result.rows]
    assert len((tmp_path / "out" / CSV).read_text().splitlines()) == 1 + 8


def test_second_run_runs_nothing_and_a_bad_scene_is_an_error_row(tmp_path, models):
    spec = read_spec(_write_spec(tmp_path, ["box.obj", "nan.obj", "missing.stl"]))
    first = run_sweep(spec, tmp_path / "out", plot=False)
    assert first.ran == 12 and first.failed == 8
    errors = {r["scene"]: r["error"] for r in first.rows if r["status"] == "error"}
    assert "nan.obj" in errors["nan"] and "NaN" in errors["nan"]
    assert "FileNotFoundError" in errors["missing"]
    cells = sorted((tmp_path / "out" / "cells").iterdir())
    stamps = [p.stat().st_mtime_ns for p in cells]
    second = run_sweep(spec, tmp_path / "out", plot=False)
    assert second.ran == 0 and second.rows == first.rows
    assert [p.stat().st_mtime_ns for p in cells] == stamps
    assert run_sweep(spec, tmp_path / "out", retry_failed=True, plot=False).ran == 8


def test_ctrl_c_keeps_the_finished_cells(tmp_path, models):
    spec = read_spec(_write_spec(tmp_path, ["box.obj", "gen:five_spheres"]))

    def interrupt_after_three(done, failed, total):
        if done == 3:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        run_sweep(spec, tmp_path / "out", progress=interrupt_after_three, plot=False)
    assert len(list((tmp_path / "out" / "cells").glob("*.json"))) == 3
    assert len(pq.read_table(tmp_path / "out" / PARQUET)) == 3  # the table of what finished
    # which says so (it looked complete: only the exit status and stderr told)
    assert "**Incomplete: 3 of 8 cells**" in (tmp_path / "out" / "summary.md").read_text()
    assert run_sweep(spec, tmp_path / "out", plot=False).ran == 5
    assert "Incomplete" not in (tmp_path / "out" / "summary.md").read_text()


#: A process of its own group: inside _workers_deaf_to_ctrl_c, a child it spawns and the Ctrl-C a
#: terminal sends to the group (os.killpg), then what came of it.
_DEAF = """
import os, signal, subprocess, sys, time
from bvhlab.sweep.runner import _workers_deaf_to_ctrl_c
try:
    with _workers_deaf_to_ctrl_c():
        child = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(30)"])
        time.sleep(0.5)
        ignored = int(open(f"/proc/{child.pid}/status").read().split("SigIgn:")[1].split()[0], 16)
        print("child ignores", bool(ignored >> (signal.SIGINT - 1) & 1), flush=True)
        if sys.argv[1] == "ctrl-c":
            os.killpg(0, signal.SIGINT)
            time.sleep(0.5)
        child.kill()
    print("no interrupt", flush=True)
except KeyboardInterrupt:
    child.kill()
    print("KeyboardInterrupt", flush=True)
"""


@pytest.mark.parametrize("sent", ["ctrl-c", "nothing"])
def test_ctrl_c_while_the_workers_start_is_raised_once_they_are_up(sent):
    # the workers start with Ctrl-C ignored, and so did this process: one while they started was
    # lost (the sweep ran to its end, exit status 0)
    got = subprocess.run(
        [sys.executable, "-c", _DEAF, sent],
        capture_output=True,
        text=True,
        timeout=60,
        start_new_session=True,
        preexec_fn=default_sigint,
    )
    assert got.stdout.split("\n")[0] == "child ignores True", got.stdout + got.stderr
    assert got.stdout.split("\n")[1] == ("KeyboardInterrupt" if sent == "ctrl-c" else "no interrupt"), got.stderr


def _without_varying(rows):
    return sorted(({k: v for k, v in r.items() if k not in VARYING} for r in rows), key=lambda r: r["key"])


@pytest.mark.slow
def test_two_worker_cluster_gives_the_in_process_table(tmp_path, models):
    spec = read_spec(_write_spec(tmp_path, ["ball.ply", "box.obj", "nan.obj", "gen:five_spheres"]))
    alone = run_sweep(spec, tmp_path / "alone", plot=False)
    cluster, client = local_cluster(2)
    with cluster, client:
        distributed = run_sweep(spec, tmp_path / "dask", client=client, plot=False)
    assert distributed.ran == 16 and distributed.failed == alone.failed == 4
    assert _without_varying(distributed.rows) == _without_varying(alone.rows)
    workers = {r["worker"] for r in distributed.rows}
    assert all(w.startswith("tcp://") for w in workers) and {r["workers_on_host"] for r in distributed.rows} == {2}


@pytest.mark.slow
def test_killing_a_worker_mid_sweep_still_completes(tmp_path, models):
    spec = read_spec(_write_spec(tmp_path, ["ball.ply", "box.obj"], rays=100_000))
    cluster, client = local_cluster(2)
    with cluster, client:
        pids = sorted(client.run(os.getpid).values())
        killed = []

        def kill_one_worker(done, failed, total):
            if done == 1 and not killed:
                os.kill(pids[0], signal.SIGKILL)
                killed.append(pids[0])

        result = run_sweep(spec, tmp_path / "out", client=client, progress=kill_one_worker, plot=False)
    assert killed and result.ran == len(result.rows) == 8
    assert result.failed == 0, [r["error"] for r in result.rows if r["status"] != "ok"]


def test_cli_sweep_in_process_and_a_bad_spec(tmp_path, models, capsys):
    spec = _write_spec(tmp_path, ["box.obj"])
    assert cli.main(["sweep", str(spec), "--out", str(tmp_path / "out"), "--workers", "0"]) == 0
    assert "4 cells (4 run now, 0 stored before), 0 failed" in capsys.readouterr().out
    assert (tmp_path / "out" / "sah_vs_build.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    bad = tmp_path / "bad.toml"
    bad.write_text(textwrap.dedent("scenes = ['box.obj']\n[grid]\nmethod = 'nope'\n"))
    assert cli.main(["sweep", str(bad), "--out", str(tmp_path / "out2"), "--workers", "0"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("bvhlab sweep: error:") and "bad.toml" in err[0]


def test_summary_divides_each_cell_by_its_baseline_cell(tmp_path, models):
    """summary.md: each row's SAH and Mrays/s over the median cell of the same scene and the same
    other settings, checked against the table's own rows; and its plot."""
    spec = read_spec(_write_spec(tmp_path, ["box.obj", "ball.ply"], "method = ['median', 'sah']\nbins = [4, 16]\n"
                                 "max_leaf_size = [1, 4]\n[report]\nbaseline = 'median'"))  # fmt: skip
    result = run_sweep(spec, tmp_path / "out")
    lines = (tmp_path / "out" / SUMMARY).read_text().splitlines()
    assert lines[0].startswith("| scene | setting | SAH cost | SAH ÷ median |") and len(lines) == 2 + len(result.rows)
    by_label = {tuple(line.split(" | ")[:2]): line.split(" | ") for line in lines[2:]}
    for row in result.rows:
        base = next(
            r for r in result.rows
            if r["scene"] == row["scene"] and r["method"] == "median" and r["max_leaf_size"] == row["max_leaf_size"]
            and r["bins"] == row["bins"]
        )  # fmt: skip
        label = f"{row['method']} b{row['bins']} leaf{row['max_leaf_size']}"
        cells = by_label[(f"| {row['scene']}", label)]
        assert float(cells[3]) == pytest.approx(row["sah_cost"] / base["sah_cost"], abs=0.006)
        assert float(cells[6].rstrip(" |")) == pytest.approx(row["mrays_per_s"] / base["mrays_per_s"], abs=0.006)
    assert (tmp_path / "out" / RATIO_PLOT).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_pareto_front_against_brute_force():
    rng = np.random.default_rng(5)
    points = [tuple(p) for p in rng.random((40, 2)).round(2)]
    front = pareto_front(points)
    beaten = {p for p in points for q in points if q != p and q[0] <= p[0] and q[1] <= p[1] and q != p}
    assert set(front) == set(points) - beaten


@pytest.mark.slow
def test_cli_sends_the_cells_to_a_running_scheduler(tmp_path, models, capsys):
    """--scheduler: the tasks go to a cluster the command did not start (here a LocalCluster's
    scheduler, as `dask scheduler` would be), and its workers' addresses are in the table."""
    spec = _write_spec(tmp_path, ["box.obj", "nan.obj"])
    cluster, client = local_cluster(2)
    with cluster, client:
        out = tmp_path / "out"
        # 1: cells failed (nan.obj's), as a script running the sweep is told
        assert cli.main(["sweep", str(spec), "--out", str(out), "--scheduler", cluster.scheduler_address]) == 1
        workers = set(client.scheduler_info()["workers"])
    assert "8 cells (8 run now, 0 stored before), 4 failed" in capsys.readouterr().out
    rows = pq.read_table(out / PARQUET).to_pylist()
    assert {r["worker"] for r in rows} <= workers


def test_a_gltf_buffer_is_part_of_the_scene_and_two_files_of_one_name_are_two_scenes(tmp_path):
    """A .gltf's geometry is in its .bin: a changed .bin is a new cell (the key hashed the .gltf
    alone: the old SAH came back from the store, and two .gltf files of one JSON were one scene);
    two meshes named alike in two folders are two scenes in the table, the plots and the summary
    (they were drawn as one 'bunny' panel with one Pareto front)."""
    for folder, extents in (("a", (1, 2, 3)), ("b", (3, 1, 1))):
        (tmp_path / folder).mkdir()
        trimesh.creation.box(extents=extents).export(tmp_path / folder / "model.gltf")
    spec = read_spec(_write_spec(tmp_path, ["a/model.gltf", "b/model.gltf"], grid="method = ['sah']"))
    cells = plan_cells(spec)
    assert len({c.key for c in cells}) == 2, "the same JSON, other buffers: two scenes"
    result = run_sweep(spec, tmp_path / "out", plot=False)
    assert sorted(r["scene"] for r in result.rows) == ["a/model.gltf", "b/model.gltf"]
    trimesh.creation.box(extents=(5, 5, 1)).export(tmp_path / "b" / "model.gltf")  # rewrites its .bin too
    again = run_sweep(spec, tmp_path / "out", plot=False)
    assert again.ran == 1
    fresh = build(load_scene(str(tmp_path / "b" / "model.gltf"))[0], method="sah").stats["sah_cost"]
    assert [r["sah_cost"] for r in again.rows if r["scene"] == "b/model.gltf"] == [pytest.approx(fresh)]


def test_a_file_changed_after_planning_is_an_error_not_another_scenes_row(tmp_path, models):
    """The scene file replaced after the sweep was planned: the cell's row was the new file's figures
    under the old file's key, and a later run reused them."""
    from bvhlab.sweep.task import run_cell

    spec = read_spec(_write_spec(tmp_path, ["box.obj"], "method = 'sah'"))
    (cell,) = plan_cells(spec)
    trimesh.creation.icosphere(subdivisions=1).export(models / "box.obj")
    row = run_cell(cell)
    assert row["status"] == "error" and "changed after the sweep was planned" in row["error"], row
    assert row["triangles"] is None


def test_a_row_of_a_file_changed_during_the_sweep_is_run_again(tmp_path, models):
    """A file rewritten while the sweep ran and then put back as planned: its error ("changed after
    the sweep was planned", or the half-written file's own) was stored under the planned file's key
    and reused by every later run, which its advice ("run the sweep again") could not mend (probe).
    Such a row is run again by the next sweep."""
    from bvhlab.sweep import task

    spec = read_spec(_write_spec(tmp_path, ["box.obj"], "method = 'sah'"))
    planned = (models / "box.obj").read_bytes()
    real_load = task.load_scene

    def load_while_rewritten(name):  # another writer is half-way through the file as it is read
        (models / "box.obj").write_bytes(planned[: len(planned) // 2])
        return real_load(name)

    task.load_scene = load_while_rewritten
    try:
        first = run_sweep(spec, tmp_path / "out", plot=False)
    finally:
        task.load_scene = real_load
        (models / "box.obj").write_bytes(planned)  # the writer done: the file as planned
    assert [r["status"] for r in first.rows] == ["error"]
    again = run_sweep(spec, tmp_path / "out", plot=False)
    assert again.ran == 1 and [r["status"] for r in again.rows] == ["ok"]
    assert again.rows[0]["triangles"] == 12


def test_summary_tells_seeds_apart(tmp_path, models):
    """Three seeds of a random-axis grid: each seed's own median is its baseline (the three rows were
    one label, each divided by the last seed's median)."""
    spec = read_spec(
        _write_spec(tmp_path, ["ball.ply"], "method = ['median', 'sah']\naxis = 'random'\nseed = [1, 2, 3]")
    )
    run_sweep(spec, tmp_path / "out", plot=False)
    lines = (tmp_path / "out" / SUMMARY).read_text().splitlines()[2:]
    medians = [line.split(" | ") for line in lines if " | median seed" in line]
    assert sorted(cells[1] for cells in medians) == ["median seed1", "median seed2", "median seed3"]
    assert all(float(cells[3]) == 1.0 for cells in medians)


def test_a_bar_in_a_scene_name_keeps_the_summary_table_in_its_columns(tmp_path, models):
    """A file "left|right.obj": its summary row had one cell more, and every figure stood under
    the heading to its left in Markdown (probe)."""
    (models / "box.obj").rename(models / "left|right.obj")
    spec = read_spec(_write_spec(tmp_path, ["left|right.obj"], "method = ['median', 'sah']"))
    run_sweep(spec, tmp_path / "out", plot=False)
    lines = (tmp_path / "out" / SUMMARY).read_text().splitlines()
    header, rows = lines[0], [line for line in lines[2:] if line.startswith("|")]
    cells = lambda line: [c for c in re.split(r"(?<!\\)\|", line)[1:-1]]  # noqa: E731
    assert len(rows) == 2 and all(len(cells(r)) == len(cells(header)) for r in rows), rows
    assert cells(rows[0])[0].strip() == "left\\|right"


def test_a_stored_row_is_named_by_the_spec_that_shows_it(tmp_path, models):
    """A second spec with a copy of a file under another name reused the first's cells (the same
    content) and took their scene name from the new spec, but its source column still named the
    first spec's file, which might be deleted by then (probe)."""
    (models / "copy").mkdir()
    (models / "copy" / "box2.obj").write_bytes((models / "box.obj").read_bytes())
    run_sweep(read_spec(_write_spec(tmp_path, ["box.obj"], "method = 'sah'")), tmp_path / "out", plot=False)
    (models / "box.obj").unlink()
    again = run_sweep(
        read_spec(_write_spec(tmp_path, ["copy/box2.obj"], "method = 'sah'")), tmp_path / "out", plot=False
    )
    assert again.ran == 0
    (row,) = again.rows
    assert row["scene"] == "box2" and Path(row["source"]).resolve() == (models / "copy" / "box2.obj").resolve(), row


def test_rays_of_a_scene_near_the_coordinate_limit_start_within_it(tmp_path):
    """Geometry at ±5e11 (within the ±2^40 range) failed every cell: the rays started on a sphere
    of the bounds' diagonal around them, outside the range (probe). Such a start is moved towards
    its target, into the range; the rays of other scenes are as before."""
    from bvhlab.scene import MAX_COORDINATE, Scene
    from bvhlab.sweep.task import fixed_rays

    far = np.array([[[-5e11, -5e11, 0], [5e11, -5e11, 0], [0, 5e11, 1e11]]], np.float32)
    origins, directions = fixed_rays(Scene(triangles=far), 5000, 1)
    assert np.abs(origins).max() <= MAX_COORDINATE
    targets = origins.astype(np.float64) + directions
    lo, hi = far.reshape(-1, 3).min(0), far.reshape(-1, 3).max(0)
    assert (targets >= lo - 1e6).all() and (targets <= hi + 1e6).all()  # still aimed into the bounds
    unit = np.random.default_rng(2).random((50, 3, 3), dtype=np.float32)
    o, d = fixed_rays(Scene(triangles=unit), 1000, 3)
    rng = np.random.default_rng(3)  # the documented rays, where nothing is out of range
    lo, hi = (b.astype(np.float64) for b in Scene(triangles=unit).bounds())
    sphere = rng.normal(size=(1000, 3))
    sphere /= np.linalg.norm(sphere, axis=1, keepdims=True)
    start = (lo + hi) / 2 + np.linalg.norm(hi - lo) * sphere
    np.testing.assert_array_equal(o, start.astype(np.float32))
    np.testing.assert_array_equal(d, (lo + rng.random((1000, 3)) * (hi - lo) - start).astype(np.float32))
    (tmp_path / "far.obj").write_text("v -5e11 -5e11 0\nv 5e11 -5e11 0\nv 0 5e11 1e11\nf 1 2 3\n")
    result = run_sweep(read_spec(_write_spec(tmp_path, ["far.obj"], "method = 'sah'")), tmp_path / "out", plot=False)
    assert [r["status"] for r in result.rows] == ["ok"] and result.rows[0]["hits"] > 0


def test_a_sweep_whose_cells_all_fail_says_so_and_keeps_no_old_plot(tmp_path, models, capsys):
    # it exited 0, and the plots of an earlier spec's cells stood beside the new table
    out = tmp_path / "out"
    assert cli.main(["sweep", str(_write_spec(tmp_path, ["box.obj"])), "--out", str(out), "--workers", "0"]) == 0
    assert (out / "sah_vs_build.png").exists() and (out / RATIO_PLOT).exists()
    failing = tmp_path / "failing"
    failing.mkdir()
    spec = _write_spec(failing, ["nan.obj"])
    capsys.readouterr()
    assert cli.main(["sweep", str(spec), "--out", str(out), "--workers", "0"]) == 1
    assert "4 of 4 cells failed" in capsys.readouterr().err
    assert not (out / "sah_vs_build.png").exists() and not (out / RATIO_PLOT).exists()
