"""Batch queries on a thread with a small stack. A piece of a batch keeps its rays, hits and scale
factors on the calling thread's stack (ray_batch.h: a 32 KiB thread runs them since the pieces are
256 rays; with 1,024-ray chunks a 64 KiB thread crashed), so
the bound is pinned here: a thread of 256 KiB, half of the smallest default any supported platform
gives a thread (macOS: 512 KiB; Linux 8 MiB, Windows 1 MiB), runs every batch query, flat and
two-level, with the same results as the main thread. A batch query that grew its stack frame past
it crashes this test's process instead of a user's Blender."""

import threading

import numpy as np

import bvhlab
from bvhlab.library import procedural

STACK = 256 * 1024


def _queries(tree, origins, directions):
    hits = tree.intersect(origins, directions, threads=1)
    blocked = tree.occluded(origins, directions, threads=1)
    return hits, blocked


def _on_small_stack(fn):
    out, errors = {}, []

    def run():
        try:
            out["value"] = fn()
        except BaseException as e:  # reported to the test, not lost on the thread
            errors.append(e)

    old = threading.stack_size(STACK)
    try:
        t = threading.Thread(target=run)
        t.start()
        t.join()
    finally:
        threading.stack_size(old)
    if errors:
        raise errors[0]
    return out["value"]


def _rays(n=5000, seed=1):
    rng = np.random.default_rng(seed)
    origins = rng.uniform(-2.5, 2.5, (n, 3)).astype(np.float32)
    directions = rng.normal(size=(n, 3)).astype(np.float32)
    return origins, directions


def _check_same(tree, origins, directions):
    hits, blocked = _on_small_stack(lambda: _queries(tree, origins, directions))
    want_hits, want_blocked = _queries(tree, origins, directions)
    assert np.isfinite(want_hits["t"]).sum() > len(origins) // 10  # the rays hit something
    for key in want_hits:
        np.testing.assert_array_equal(hits[key], want_hits[key], err_msg=key)
    np.testing.assert_array_equal(blocked, want_blocked)


def test_flat_tree_batches_on_a_small_stack():
    tree = bvhlab.build(procedural.torus_knot(40_000))
    _check_same(tree, *_rays())


def test_two_level_batches_on_a_small_stack():
    knot = procedural.torus_knot(5000)
    transforms = np.zeros((4, 3, 4), np.float32)
    for i in range(4):
        transforms[i, :, :3] = np.eye(3) * (0.5 + 0.25 * i)
        transforms[i, :, 3] = (i - 1.5, 0.3 * i, 0.0)
    scene = bvhlab.Scene(triangles=knot, instance_mesh=np.zeros(4, np.int64), instance_transforms=transforms)
    _check_same(bvhlab.build(scene), *_rays(seed=2))
