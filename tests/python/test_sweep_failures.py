"""`bvhlab sweep` where things go wrong around the cells (helper probe, issue 37): a scheduler lost
mid-sweep, one that never answers or speaks another protocol, an interrupt while the table and its
plots are written, an empty --out, workers of several threads sharing the scene cache, and the
baseline of method labels' bins."""

import json
import socket
import threading
import time
from pathlib import Path

import numpy as np
import pytest
import trimesh

from bvhlab import cli
from bvhlab.cli import sweep_cmd
from bvhlab.sweep import local_cluster, plan_cells, read_spec, run_sweep, runner, task
from bvhlab.sweep.summary import RATIO_PLOT, SUMMARY, baseline_pairs, setting_labels
from bvhlab.sweep.table import CSV


def _spec(folder: Path, scenes, grid: str, rays: int = 2000) -> Path:
    path = folder / "spec.toml"
    path.write_text(f"scenes = {json.dumps(scenes)}\n[grid]\n{grid}\n[rays]\ncount = {rays}\n")
    return path


def _soup(path: Path, triangles: int, seed: int) -> Path:
    rng = np.random.default_rng(seed)
    corners = rng.random((triangles, 1, 3)) * 10 + rng.normal(0, 0.3, (triangles, 3, 3))
    trimesh.Trimesh(corners.reshape(-1, 3), np.arange(3 * triangles).reshape(-1, 3), process=False).export(path)
    return path


def _stored(out: Path) -> list[dict]:
    return [json.loads(p.read_text()) for p in (out / "cells").glob("*.json")]


@pytest.mark.slow
def test_cells_of_a_lost_scheduler_are_not_stored_and_the_same_command_runs_them(tmp_path):
    """The cluster closed mid-sweep: its cancelled tasks never ran, so nothing is stored for them
    (they were stored as errors, failures for good: only --retry-failed ran them again)."""
    _soup(tmp_path / "soup.ply", 20_000, 1)
    grid = "method = ['median', 'sah', 'mean', 'lbvh']\nmax_leaf_size = [1, 2, 3, 4, 5, 6]"
    spec = read_spec(_spec(tmp_path, ["soup.ply"], grid, rays=100_000))
    out = tmp_path / "out"
    cluster, client = local_cluster(2)
    outcome: dict = {}

    def sweep():
        try:
            outcome["result"] = run_sweep(spec, out, client=client)
        except BaseException as error:  # noqa: BLE001 (looked at below)
            outcome["error"] = error

    worker = threading.Thread(target=sweep)
    worker.start()
    deadline = time.monotonic() + 120
    while not list((out / "cells").glob("*.json")) and time.monotonic() < deadline:
        time.sleep(0.02)
    cluster.close()
    worker.join(120)
    client.close()
    assert isinstance(outcome.get("error"), runner.CellsNotRun), outcome
    stored = _stored(out)
    assert 0 < len(stored) < 24 and all(r["status"] == "ok" for r in stored)
    assert f"{24 - len(stored)} of 24 cells were not run" in str(outcome["error"])
    again = run_sweep(spec, out)  # in this process: the rest, none counted as failed
    assert again.ran == 24 - len(stored) and again.failed == 0


class _Listener:
    """A TCP server on localhost that accepts and then `answer`s each connection (None: says nothing)."""

    def __init__(self, answer: bytes | None):
        self.sock = socket.create_server(("127.0.0.1", 0))
        self.address = f"tcp://127.0.0.1:{self.sock.getsockname()[1]}"
        self.answer, self.conns = answer, []
        threading.Thread(target=self._serve, daemon=True).start()

    def _serve(self):
        while True:
            try:
                conn, _ = self.sock.accept()
            except OSError:
                return
            self.conns.append(conn)
            if self.answer is not None:
                conn.recv(65536)
                conn.sendall(self.answer)

    def close(self):
        for conn in self.conns:
            conn.close()
        self.sock.close()


@pytest.mark.parametrize(
    "answer, why",
    [(None, "did not answer within 1 s"), (b"HTTP/1.1 400 Bad Request\r\n\r\n", "does not speak Dask's protocol")],
    ids=["silent", "http"],
)
def test_a_scheduler_address_that_does_not_answer_as_dask_is_an_error(tmp_path, monkeypatch, capsys, answer, why):
    """A peer that accepts and never answers held the sweep for good (Dask's timeout bounds the
    connection only); an HTTP server's reply read as a message of exabytes: "out of memory"."""
    monkeypatch.setattr(sweep_cmd, "CONNECT_S", 1.0)
    trimesh.creation.box().export(tmp_path / "box.obj")
    server = _Listener(answer)
    try:
        start = time.monotonic()
        code = cli.main(["sweep", str(_spec(tmp_path, ["box.obj"], "method = 'median'")), "--out",
                         str(tmp_path / "out"), "--scheduler", server.address])  # fmt: skip
        took = time.monotonic() - start
    finally:
        server.close()
    err = capsys.readouterr().err
    assert code == 2 and took < 15, (code, took)
    assert f"no Dask scheduler at {server.address}" in err and why in err, err


def test_an_empty_out_is_refused(tmp_path, monkeypatch, capsys):
    trimesh.creation.box().export(tmp_path / "box.obj")
    monkeypatch.chdir(tmp_path)
    with pytest.raises(SystemExit) as exit_:
        cli.main(["sweep", str(_spec(tmp_path, ["box.obj"], "method = 'median'")), "--out", "", "--workers", "0"])
    assert exit_.value.code == 2 and "the output folder is empty" in capsys.readouterr().err
    assert not (tmp_path / "cells").exists() and not (tmp_path / CSV).exists()


def test_an_interrupt_while_the_results_are_written_leaves_the_last_runs_files_together(tmp_path, monkeypatch):
    """The table, its plots and its summary move in together: a Ctrl-C while the summary was made
    left the new table beside the last run's summary and plots (helper probe)."""
    trimesh.creation.box().export(tmp_path / "box.obj")
    out = tmp_path / "out"
    run_sweep(read_spec(_spec(tmp_path, ["box.obj"], "method = ['median', 'sah']")), out)
    before = {name: (out / name).read_bytes() for name in (CSV, SUMMARY, "sah_vs_build.png")}

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(runner, "write_summary", interrupted)
    bigger = read_spec(_spec(tmp_path, ["box.obj"], "method = ['median', 'sah', 'mean']"))
    with pytest.raises(KeyboardInterrupt):
        run_sweep(bigger, out)
    assert {name: (out / name).read_bytes() for name in before} == before
    assert len(_stored(out)) == 3  # the cell that finished is kept
    assert not [p for p in out.iterdir() if p.name.startswith(".staged")]


def test_threads_of_one_worker_each_get_their_cells_scene(tmp_path):
    """A worker of several threads runs several cells at once: each thread keeps its own last scene
    (one module-wide cache gave a cell another scene's figures, or None, where a thread's read of
    it came after another's write: found by pausing inside the cache, as here)."""
    for k in range(8):
        _soup(tmp_path / f"s{k}.ply", 100 + 10 * k, k)
    spec = read_spec(_spec(tmp_path, [f"s{k}.ply" for k in range(8)], "method = ['median', 'mean']", rays=200))
    cells = plan_cells(spec)

    def tracer(frame, event, arg):  # every line of _scene pauses
        if frame.f_code is not task._scene.__code__:
            return None

        def pause(frame, event, arg):
            if event == "line":
                time.sleep(0.002)
            return pause

        return pause

    rows: list[dict] = []
    lock = threading.Lock()

    def work(mine):
        for cell in mine:
            row = task.run_cell(cell)
            with lock:
                rows.append(row)

    threading.settrace(tracer)
    try:
        threads = [threading.Thread(target=work, args=(cells[i::4],)) for i in range(4)]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
    finally:
        threading.settrace(None)
    assert len(rows) == len(cells) and all(r["status"] == "ok" for r in rows), [r["error"] for r in rows]
    for row in rows:
        assert row["triangles"] == 100 + 10 * int(Path(row["source"]).stem[1:]), row


def test_method_labels_bins_are_divided_by_the_baseline_and_labelled_where_they_vary(tmp_path):
    """The report's Table 1 methods (median, mean, sah12, sah32): sah32's cells had no median cell of
    32 bins to divide by (its ratios '–'), and every label said b12, the median's too."""
    trimesh.creation.icosphere(subdivisions=2).export(tmp_path / "ball.ply")
    grid = "method = ['median', 'mean', 'sah12', 'sah32']\nmax_leaf_size = [1, 4]"
    result = run_sweep(read_spec(_spec(tmp_path, ["ball.ply"], grid)), tmp_path / "out")
    pairs = baseline_pairs(result.rows, "median")
    assert len(pairs) == 8 and all(base is not None for _, base in pairs)
    for row, base in pairs:
        assert base["method"] == "median" and base["max_leaf_size"] == row["max_leaf_size"]
    labels = setting_labels(result.rows)
    assert {labels[r["key"]] for r in result.rows if r["method"] != "sah"} == {
        f"{m} leaf{n}" for m in ("median", "mean") for n in (1, 4)
    }
    assert {labels[r["key"]] for r in result.rows if r["method"] == "sah"} == {
        f"sah b{b} leaf{n}" for b in (12, 32) for n in (1, 4)
    }
    assert "–" not in (tmp_path / "out" / SUMMARY).read_text()


def test_plots_draw_at_most_max_panels_scenes_and_bars_get_room(tmp_path, monkeypatch):
    """600 scenes drew two figures 70,000 pixels tall for minutes at every run (a Ctrl-C waited for
    them); 63 settings' bars printed their labels over each other in a fixed panel."""
    from PIL import Image

    from bvhlab.sweep import plot

    monkeypatch.setattr(plot, "MAX_PANELS", 2)
    for k in range(4):
        _soup(tmp_path / f"s{k}.ply", 50, k)
    grid = "method = ['median', 'sah', 'mean']\nmax_leaf_size = [1, 2, 3, 4, 5, 6, 7, 8]"
    run_sweep(read_spec(_spec(tmp_path, [f"s{k}.ply" for k in range(4)], grid, rays=200)), tmp_path / "out")
    with Image.open(tmp_path / "out" / "sah_vs_build.png") as chart, Image.open(tmp_path / "out" / RATIO_PLOT) as bars:
        assert chart.size[1] < 500 and bars.size[1] < 500  # one row of two panels each
        assert bars.size[1] >= 100 * (0.8 + 0.14 * 24) - 2  # 24 bars a panel: 4.2 inches at 100 dpi


def test_a_stopped_sweeps_summary_divides_by_the_planned_baseline_cell_or_none(tmp_path):
    """A table the sweep stopped in lacks some baseline cells: a setting the baseline varies in
    looked fixed, and a leaf-4 cell was divided by the leaf-2 baseline (review); it gets none."""
    trimesh.creation.icosphere(subdivisions=2).export(tmp_path / "ball.ply")
    spec = read_spec(_spec(tmp_path, ["ball.ply"], "method = ['median', 'sah']\nmax_leaf_size = [2, 4]"))
    rows = run_sweep(spec, tmp_path / "out").rows
    planned = [c.columns() for c in plan_cells(spec)]
    stopped = [r for r in rows if not (r["method"] == "median" and r["max_leaf_size"] == 4)]
    pairs = {r["max_leaf_size"]: base for r, base in baseline_pairs(stopped, "median", planned) if r["method"] == "sah"}
    assert pairs[2] is not None and pairs[2]["max_leaf_size"] == 2
    assert pairs[4] is None
    assert setting_labels(stopped, planned)[stopped[0]["key"]].endswith("leaf2")
