"""One cell's work, run in a Dask worker (or in-process): load the scene, build the tree on one
thread, and time the CPU intersect of fixed random rays. A failure becomes the row's error, so a bad
scene is recorded, not retried."""

from __future__ import annotations

import threading
import time

import numpy as np

from ..bvh import build
from ..library import load_scene
from ..scene import MAX_COORDINATE, Scene
from .cells import Cell, scene_hash

#: The columns every row has, in the table's order after the cell's own (Cell.columns).
MEASURED = (
    *("status", "error", "triangles", "spheres", "nodes", "leaves", "height", "sah_cost", "memory_bytes", "hits"),
    *("build_ms", "intersect_ms", "mrays_per_s", "worker"),
)
#: Columns that differ between two runs of the same cell (timings and where it ran).
VARYING = ("build_ms", "intersect_ms", "mrays_per_s", "worker", "workers_on_host")
_WARM_UP_RAYS = 1000

# The last scene each thread loaded: cells of one scene usually follow each other on a worker; a
# worker of several threads runs several cells at once (a module-wide cache gave a cell another
# scene's figures, or None: helper probe).
_last = threading.local()


def run_cell(cell: Cell) -> dict:
    """The cell's row (Cell.columns and MEASURED); status "ok", or "error" with the error's text."""
    row: dict = {**cell.columns(), **dict.fromkeys(MEASURED), "worker": _worker_name()}
    try:
        row.update(_measure(cell))
        row["status"] = "ok"
    except (Exception, MemoryError) as e:  # the cell's error row; Ctrl-C still stops the sweep
        row["status"], row["error"] = "error", f"{type(e).__name__}: {e}"
        if isinstance(e, SceneChanged):  # not the key's scene's error: run again next time
            row["retry"] = True
    return row


class SceneChanged(ValueError):
    """The scene file read was not the one the cell's key was made of (changed after the sweep was
    planned, or being written while it was read): its error is no figure of the key's scene, so
    its row is run again by the next sweep (runner.run_sweep) rather than reused. Stored under the
    key, it was reused when the file was back as planned, and its advice ("run the sweep again")
    did not help."""


def error_row(cell: Cell, error: BaseException | str) -> dict:
    """The row of a cell whose task never returned (a worker killed after Dask's retries)."""
    text = error if isinstance(error, str) else f"{type(error).__name__}: {error}"
    return {**cell.columns(), **dict.fromkeys(MEASURED), "status": "error", "error": text}


def _measure(cell: Cell) -> dict:
    scene = _scene(cell)
    config = cell.setting.config.replace(threads=1)  # one thread: one core per worker
    # a build untimed first: a process's first build of a scene is 3-5× slower (its memory's pages
    # faulted in, the code cold): the first cell on each worker, and so the order, changed build_ms
    build(scene, config=config)
    bvh = build(scene, config=config)
    stats = bvh.stats
    origins, directions = fixed_rays(scene, cell.rays, cell.ray_seed)
    traversal = cell.setting.traversal
    bvh.intersect(origins[:_WARM_UP_RAYS], directions[:_WARM_UP_RAYS], traversal=traversal, threads=1)
    times = []
    for _ in range(cell.repeats):  # the median pass: one pass is at the mercy of a neighbour's burst
        start = time.perf_counter()
        hits = bvh.intersect(origins, directions, traversal=traversal, threads=1)
        times.append(time.perf_counter() - start)
    seconds = float(np.median(times))
    return {
        **{k: stats[k] for k in ("triangles", "spheres", "nodes", "leaves", "height", "sah_cost", "memory_bytes")},
        "hits": int(np.isfinite(hits["t"]).sum()),
        "build_ms": stats["build_ms"],
        "intersect_ms": seconds * 1e3,  # the median of the repeats
        "mrays_per_s": len(origins) / seconds / 1e6 if seconds > 0 else float("nan"),
    }


def fixed_rays(scene: Scene, count: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """`count` rays, the same for a given scene and seed on every machine: each starts on the sphere
    around the scene's bounds and aims at a uniformly random point inside them; where that start
    lies outside the coordinate range (a scene near ±MAX_COORDINATE, valid geometry), it is moved
    along the ray towards its target until within it (every cell of such a scene failed: "ray 0
    starts outside the supported coordinate range")."""
    rng = np.random.default_rng(seed)
    lo, hi = (b.astype(np.float64) for b in scene.bounds())
    centre, radius = (lo + hi) / 2, max(float(np.linalg.norm(hi - lo)), 1e-6)
    on_sphere = rng.normal(size=(count, 3))
    on_sphere /= np.linalg.norm(on_sphere, axis=1, keepdims=True)
    origins = centre + radius * on_sphere
    targets = lo + rng.random((count, 3)) * (hi - lo)
    limit = 0.999 * MAX_COORDINATE  # float32's rounding of the start stays within the range
    outside = np.abs(origins) > limit
    if outside.any():
        way = origins - targets  # targets lie within the bounds, so within the range
        with np.errstate(divide="ignore", invalid="ignore"):
            share = np.where(outside, (np.sign(origins) * limit - targets) / way, 1.0)
        origins = targets + np.minimum(share.min(axis=1), 1.0)[:, None] * way
    return origins.astype(np.float32), (targets - origins).astype(np.float32)


def _scene(cell: Cell) -> Scene:
    if not cell.scene_hash:
        load_scene(cell.scene)  # raises what is wrong (missing file, unknown name)
        raise ValueError(f"{cell.scene} could not be read when the sweep was planned")
    key = (cell.scene, cell.scene_hash)
    last = getattr(_last, "scene", None)
    if last is None or last[0] != key:
        _last.scene = None  # free the old scene before loading the next
        try:
            scene = load_scene(cell.scene)[0]
        except Exception as e:  # a file half-written as it was read is no error of the key's scene
            if scene_hash(cell.scene) != cell.scene_hash:
                raise SceneChanged(f"{cell.scene} changed after the sweep was planned ({e})") from e
            raise
        # what was loaded must be what the cell's key says: a file replaced after the sweep was
        # planned (or another host's copy of the path) stored another scene's figures under the
        # key, and later runs reused them
        if scene_hash(cell.scene, scene) != cell.scene_hash:  # a generated scene's from its arrays
            raise SceneChanged(f"{cell.scene} changed after the sweep was planned: it is run again next time")
        last = _last.scene = (key, scene)
    return last[1]


def _worker_name() -> str:
    try:
        from distributed import get_worker

        return get_worker().address
    except (ImportError, ValueError):  # not in a Dask worker
        return "in-process"
