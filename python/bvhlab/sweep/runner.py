"""Running a sweep's cells: in this process, or as one Dask task each on a `distributed` cluster (a
LocalCluster of single-threaded worker processes, or a running scheduler). Each finished cell is
stored at once; cells already stored are not run again; a task that fails after Dask's retries (a
worker killed) is recorded with its error; Ctrl-C cancels what is left and keeps what finished."""

from __future__ import annotations

import contextlib
import os
import signal
import subprocess
import sys
import threading
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from .._atomic import deliver_interrupt, staged_folder
from .cells import Cell, plan_cells
from .plot import PLOT, plot_sah_against_build_time
from .spec import SweepSpec
from .summary import RATIO_PLOT, write_summary
from .table import store_row, stored_rows, write_table
from .task import MEASURED, error_row, run_cell

#: Dask's retries of a task that did not return (its worker died); Dask's own allowed-failures
#: (3 by default) also ends a task that kills every worker it lands on.
TASK_RETRIES = 1

#: progress(done, failed, total): called once before the first cell and after each.
Progress = Callable[[int, int, int], None]


@dataclass
class SweepResult:
    rows: list[dict]  # one per cell of the spec, in its order
    ran: int  # cells run this time (the others were stored already)
    failed: int  # cells with status "error" in the table
    files: list[Path]


def run_sweep(
    spec: SweepSpec,
    out: Path,
    *,
    client=None,
    retry_failed: bool = False,
    progress: Progress | None = None,
    plot: bool = True,
) -> SweepResult:
    """Runs the spec's cells not yet stored in `out` (in this process when `client` is None, else
    as Dask tasks through `client`), then writes the table of all its cells and its summary
    (summary.py), and their plots unless `plot` is false."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    cells = plan_cells(spec)
    # a row whose scene file was not its key's (task.SceneChanged) is no result: run again
    stored = {k: r for k, r in stored_rows(out, [c.key for c in cells]).items() if not r.get("retry")}
    if retry_failed:
        stored = {k: r for k, r in stored.items() if r.get("status") == "ok"}
    todo = [c for c in cells if c.key not in stored]
    counts = _Counts(len(cells) - len(todo), sum(r.get("status") != "ok" for r in stored.values()), len(cells))
    say = progress or (lambda done, failed, total: None)
    say(counts.done, counts.failed, counts.total)

    def finished(row: dict) -> None:
        store_row(out, row)
        counts.add(row)
        say(counts.done, counts.failed, counts.total)

    try:
        if client is None:
            for cell in todo:
                finished({**run_cell(cell), "workers_on_host": 1})
        else:
            _run_on_dask(client, todo, finished)
    finally:  # also after Ctrl-C: the table of what finished
        result = _write_results(out, cells, len(todo), plot, spec.baseline)
    return result


@dataclass
class _Counts:
    done: int
    failed: int
    total: int

    def add(self, row: dict) -> None:
        self.done += 1
        self.failed += row["status"] != "ok"


class CellsNotRun(RuntimeError):
    """Cells whose Dask tasks were cancelled by the cluster (the connection to the scheduler lost,
    the scheduler restarted): they never ran, so nothing is stored for them and the same command
    runs them again (stored as errors, they were failures for good: only --retry-failed ran them)."""


def _run_on_dask(client, todo: list[Cell], finished: Callable[[dict], None]) -> None:
    from concurrent.futures import CancelledError

    from distributed import as_completed

    per_host = Counter(w["host"] for w in client.scheduler_info()["workers"].values())
    futures = {
        client.submit(run_cell, cell, key=f"bvhlab-cell-{cell.key}", retries=TASK_RETRIES): cell for cell in todo
    }
    lost: list[str] = []  # why each cancelled task was cancelled
    try:
        for future in as_completed(futures):
            cell = futures[future]
            try:
                row = future.result()
            except CancelledError as e:  # not by this sweep (it cancels only on its way out): not run
                lost.append(str(e))
                continue
            except Exception as e:  # KilledWorker and the like: the task ran and never returned a row
                row = error_row(cell, e)
            host = str(row.get("worker") or "").removeprefix("tcp://").rpartition(":")[0]
            finished({**row, "workers_on_host": per_host.get(host)})
            future.release()
    finally:  # Ctrl-C: nothing left running for this sweep (best effort: the table comes first)
        with contextlib.suppress(Exception):
            client.cancel(list(futures))
    if lost:
        reason = lost[0].rpartition("reason: ")[2].rstrip(".") or "none given"
        raise CellsNotRun(
            f"{len(lost)} of {len(todo)} cells were not run: the cluster cancelled their tasks (the scheduler "
            f"lost or closed; Dask's reason: {reason}); nothing is stored for them: the same command runs them"
        )


def _write_results(out: Path, cells: list[Cell], ran: int, plot: bool, baseline: str) -> SweepResult:
    rows_by_key = stored_rows(out, [c.key for c in cells])
    # named as this spec names them, scene and source file (a row stored by an earlier sweep keeps
    # its measurements; its source was the earlier spec's file, perhaps deleted since: probe)
    rows = [
        {**rows_by_key[c.key], **{k: c.columns()[k] for k in ("scene", "source")}}
        for c in cells
        if c.key in rows_by_key
    ]
    files: list[Path] = []
    if rows:
        columns = [*cells[0].columns(), *MEASURED, "workers_on_host"]
        # the table, its plots and its summary moved in together (a second Ctrl-C while they were
        # written left a new table beside the last run's plots and summary: helper probe)
        with staged_folder(out) as stage:
            staged = list(write_table(stage, rows, columns))
            chart = plot_sah_against_build_time(rows, stage / PLOT) if plot else None
            staged += [chart] if chart is not None else []
            staged += write_summary(rows, baseline, stage, plot=plot, planned=[c.columns() for c in cells])
            files = [out / p.relative_to(stage) for p in staged]
        for name in (PLOT, RATIO_PLOT):  # an earlier run's plot that this table no longer has
            if plot and out / name not in files:
                (out / name).unlink(missing_ok=True)
    return SweepResult(rows, ran, sum(r.get("status") != "ok" for r in rows), files)


def local_cluster(workers: int | None = None):
    """A Dask LocalCluster of `workers` processes (default: one per core), one thread each, so that
    timings are not disturbed by a neighbour's threads; and a client on it."""
    import logging

    from distributed import Client, LocalCluster

    n = workers or os.cpu_count() or 1
    cluster = None
    try:
        with _workers_deaf_to_ctrl_c():
            cluster = LocalCluster(
                n_workers=n, threads_per_worker=1, processes=True, dashboard_address=":0", silence_logs=logging.ERROR
            )
    except BaseException:
        if cluster is not None:  # a Ctrl-C while the workers started: the cluster is up, closed again
            cluster.close()
        raise
    return cluster, Client(cluster)


#: The Ctrl-C watch's program (_workers_deaf_to_ctrl_c): 'r' once its handler is in, 'c' for each
#: Ctrl-C, until its stdin closes.
_CTRL_C_WATCH = (
    "import signal, sys\n"
    "out = sys.stdout.buffer\n"
    "signal.signal(signal.SIGINT, lambda *_: out.write(b'c'))\n"
    "out.write(b'r'); out.flush()\n"
    "sys.stdin.buffer.read()\n"
    "out.flush()\n"
)


@contextlib.contextmanager
def _workers_deaf_to_ctrl_c():
    """The workers of a cluster started inside start with Ctrl-C ignored (a process inherits an
    ignored signal, and Python then installs no KeyboardInterrupt handler): Ctrl-C in a terminal
    reaches the whole process group, and only this process should act on it (cancelling the tasks,
    closing the cluster). This process ignores it meanwhile too (one disposition for the process
    and the children it spawns), so a watch process of the same group, started first, sees the
    Ctrl-C a terminal sends meanwhile, which is raised here once the workers are up (ignored alone,
    it was lost: the sweep ran to its end and exited 0)."""
    previous = signal.getsignal(signal.SIGINT)
    if threading.current_thread() is not threading.main_thread() or previous in (None, signal.SIG_IGN):
        yield  # off the main thread, or SIGINT ignored or handled outside Python: left as it is
        return
    watch = subprocess.Popen(
        [sys.executable, "-I", "-S", "-c", _CTRL_C_WATCH],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        stderr=subprocess.DEVNULL,
    )
    assert watch.stdin is not None and watch.stdout is not None
    seen = b""
    try:
        seen = watch.stdout.read(1)  # b"r": its handler is in (a Ctrl-C before: raised here)
        signal.signal(signal.SIGINT, signal.SIG_IGN)
        try:
            yield
        finally:
            signal.signal(signal.SIGINT, previous)
    finally:
        watch.stdin.close()
        seen += watch.stdout.read()
        watch.wait()
    if b"c" in seen:
        deliver_interrupt(previous)
