"""What a Bvh reads as a whole comes from one version of the tree when another thread publishes a
new one meanwhile (probe): `save` (a file that loads) and `stats` (never kept stale). The other
thread is stood in for by a core that publishes a new version after each call, so the test does
not depend on timing; a short real race runs too."""

import threading
import time

import numpy as np

import bvhlab
from bvhlab import _core
from bvhlab.library import procedural


class _Busy:
    """The tree's core, with a writer on another thread that publishes a new version (an optimize
    or a refit) right after each call reads from it."""

    def __init__(self, core, write):
        self._real, self._write = core, write

    def __getattr__(self, name):
        value = getattr(self._real, name)
        if not callable(value):
            self._write()
            return value

        def call(*args, **kwargs):
            result = value(*args, **kwargs)
            self._write()
            return result

        return call


def test_save_writes_one_version_while_the_tree_changes(tmp_path):
    tris = procedural.random_triangles(2000, size=0.05, seed=6)
    moved = np.ascontiguousarray(tris * np.float32(1.5))
    bvh = bvhlab.build(tris)
    k = [0]

    def write():  # alternately an optimisation (new topology) and a refit to the other geometry
        k[0] += 1
        if k[0] % 2:
            _core.optimize_bvh(real, bvhlab.OptimizeConfig(iterations=1).core(), None)
        else:
            real.refit(moved if k[0] % 4 == 2 else tris, None)

    real = bvh._core
    bvh._core = _Busy(real, write)
    for n in range(4):
        path = tmp_path / f"t{n}.bvhtree"
        bvh.save(path)
        loaded = [g for g in (tris, moved) if _loads(path, g)]
        assert len(loaded) == 1, f"save {n} wrote a file that loads over {len(loaded)} geometries"
    bvh._core = real


def _loads(path, tris) -> bool:
    try:
        bvhlab.load_bvh(path, tris)
    except ValueError:
        return False
    return True


def test_stats_of_an_old_version_are_not_kept():
    tris = procedural.random_triangles(500, size=0.05, seed=7)
    bvh = bvhlab.build(tris)
    real = bvh._core
    bvh._core = _Busy(real, lambda: real.refit(np.ascontiguousarray(tris * np.float32(3)), None))
    bvh.stats  # noqa: B018 (read while the tree changes)
    bvh._core = real
    assert bvh.stats["sah_cost"] == real.stats()["sah_cost"]


def test_saves_racing_updates_all_load(tmp_path):
    tris = procedural.random_triangles(3000, size=0.05, seed=8)
    moved = np.ascontiguousarray(tris + np.float32(0.3))
    bvh = bvhlab.build(tris)
    stop = time.monotonic() + 1.5
    failures = []

    def writer():
        k = 0
        while time.monotonic() < stop:
            if k % 3 == 2:
                bvh.optimize(iterations=2)
            else:
                bvh.update(moved if k % 2 else tris, policy="refit")
            k += 1

    def saver():
        n = 0
        while time.monotonic() < stop:
            path = tmp_path / f"s{n % 4}.bvhtree"
            bvh.save(path)
            if not (_loads(path, tris) or _loads(path, moved)):
                failures.append(n)
            n += 1

    threads = [threading.Thread(target=writer), threading.Thread(target=saver)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert not failures, f"saves {failures[:5]} wrote files that do not load"
