"""`bvhlab sweep SPEC.toml --out DIR`: build statistics (SAH cost, height, nodes, memory, build time)
and CPU intersect throughput (Mrays/s on fixed random rays) for every scene and grid setting of the
spec, one Dask task per cell: on a LocalCluster of single-threaded worker processes (one per core,
or --workers N), on a running Dask cluster (--scheduler tcp://HOST:8786), or in this process
(--workers 0). Writes DIR/results.parquet, DIR/results.csv and DIR/sah_vs_build.png; cells already
in DIR are not run again, so an interrupted sweep continues where it stopped. Exits 1 when a cell
failed (its row holds the error) or was not run (the scheduler lost: the same command runs it), 2
for a bad spec or a scheduler that does not answer, 130 on Ctrl-C."""

from __future__ import annotations

import argparse
import contextlib
import sys
import threading
from pathlib import Path

from .._folder_lock import folder_lock
from .._progress import ProgressBar
from . import compare_args as cargs
from . import options


def add_parser(sub) -> None:
    p = sub.add_parser(
        "sweep", help="build stats and ray throughput over scenes × settings, on Dask", description=__doc__
    )
    p.add_argument("spec", type=Path, metavar="SPEC.toml", help="the scenes and the grid of build settings")
    p.add_argument("--out", type=cargs.output_dir, required=True, help="directory for the cells, table and plot")
    where = p.add_mutually_exclusive_group()
    where.add_argument(
        "--scheduler", type=_address, metavar="tcp://HOST:PORT", help="a running Dask scheduler's address"
    )
    where.add_argument(
        "--workers",
        type=lambda text: options.whole_number(text, 0, 4096),
        help="LocalCluster worker processes (default: one per core; 0: run the cells in this process)",
    )
    p.add_argument("--retry-failed", action="store_true", help="run cells stored with an error again")
    p.set_defaults(run=run)


def run(args) -> int:
    from ..sweep import local_cluster, read_spec, run_sweep
    from ..sweep.runner import CellsNotRun

    spec = read_spec(args.spec)  # checked before a cluster starts
    _require_sweep_packages()
    args.out.mkdir(parents=True, exist_ok=True)
    with folder_lock(args.out, "bvhlab sweep"), contextlib.ExitStack() as stack:
        client = None
        if args.scheduler is not None:
            client = stack.enter_context(_connect(args.scheduler))
        elif args.workers != 0:
            cluster, client = local_cluster(args.workers)
            stack.enter_context(cluster)
            stack.enter_context(client)
        bar = stack.enter_context(ProgressBar("sweep"))
        try:
            result = run_sweep(spec, args.out, client=client, retry_failed=args.retry_failed, progress=_drawer(bar))
        except CellsNotRun as lost:  # the table of what finished is written
            print(f"bvhlab sweep: {lost}", file=sys.stderr)
            return 1
    print(
        f"sweep: {len(result.rows)} cells ({result.ran} run now, {len(result.rows) - result.ran} stored before), "
        f"{result.failed} failed"
    )
    for path in result.files:
        print(f"wrote {path}")
    if result.failed:  # a script running the sweep is told (it exited 0 with every cell failed)
        print(
            f"bvhlab sweep: {result.failed} of {len(result.rows)} cells failed (their rows hold the errors)",
            file=sys.stderr,
        )
        return 1
    return 0


def _drawer(bar: ProgressBar):
    def draw(done: int, failed: int, total: int) -> None:
        bar.label = f"sweep {done}/{total} done, {failed} failed, {total - done} left"
        bar(done / total if total else 1.0)

    return draw


def _require_sweep_packages() -> None:
    try:
        import distributed  # noqa: F401
        import pyarrow  # noqa: F401
    except ImportError as e:
        raise RuntimeError(
            f"bvhlab sweep needs dask[distributed] and pyarrow ({e}): pip install 'bvhlab[sweep]'"
        ) from None


#: How long (s) a scheduler has to answer, the connection and Dask's handshake both.
CONNECT_S = 20.0


def _connect(address: str):
    """A client of the Dask scheduler at `address`, or a SchedulerUnreachable after CONNECT_S.
    Dask's own timeout bounds the connection only: a peer that accepts it and never answers held
    the sweep for good, and one that answers in another protocol (an HTTP server) read as a
    message length of exabytes, "out of memory" (helper probe). So the client is made on a daemon
    thread and waited for."""
    from distributed import Client

    made: dict = {}

    def connect() -> None:
        try:
            made["client"] = Client(address, timeout=f"{CONNECT_S:g}s")
        except BaseException as error:  # noqa: BLE001 (handed to the caller's thread)
            made["error"] = error

    thread = threading.Thread(target=connect, name="bvhlab-sweep-connect", daemon=True)
    thread.start()
    thread.join(CONNECT_S + 5)
    if "client" in made:
        return made["client"]
    error = made.get("error")
    if thread.is_alive():
        why = f"it accepted the connection but did not answer within {CONNECT_S:g} s"
    elif isinstance(error, MemoryError):
        why = "what answered does not speak Dask's protocol"
    else:
        why = f"{type(error).__name__}: {error}"
    raise SchedulerUnreachable(f"no Dask scheduler at {address}: {why}")


class SchedulerUnreachable(RuntimeError):
    """--scheduler names no scheduler that answers."""


def _address(text: str) -> str:
    """A scheduler's address; an empty one is refused (it ran a local cluster instead, silently)."""
    if not text.strip():
        raise argparse.ArgumentTypeError("the scheduler's address is empty (e.g. tcp://10.0.0.5:8786)")
    return text.strip()
