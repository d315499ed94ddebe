"""Batch queries on a thread with a small stack. A batch keeps its pieces' rays and hits, the
packet walk's stack and the interleaved walkers off the calling thread's stack (ray_batch.h
RayPiece; wide_traverse.inl thread_room): its frames are a few KiB, so the bound is pinned here at
the least Python allows, 32 KiB (a thread of 48 KiB crashed on a batch whose block was probed and
sorted: the probe's two pieces and the chunk's made 53 KiB of frames). Every batch query runs
there with the same results as on the main thread: flat, in each of its ways (a block probed,
sorted and interleaved; a block timed; camera rays as packets; a batch too small to probe), and
two-level (ray by ray).
A batch query that grew its frames past it crashes this test's process instead of a user's
Blender."""

import threading

import numpy as np

import bvhlab
from bvhlab.library import procedural

STACK = 32 * 1024  # threading.stack_size's least


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


def _visited(tree, origins, directions) -> float:
    return float(tree.intersect(origins, directions, nodes_visited=True)["nodes_visited"].mean())


def test_probed_sorted_and_interleaved_batches_on_a_small_stack():
    # many small triangles: random rays visit at least 8 wide nodes (bvhlab's kOrderNodes), so a
    # block of them is probed, sorted and walked interleaved; 3,000 are too few to probe
    tris = procedural.random_triangles(60_000, size=0.08, seed=3)
    lo, hi = tris.reshape(-1, 3).min(0), tris.reshape(-1, 3).max(0)
    tree = bvhlab.build(tris)
    rng = np.random.default_rng(4)
    for n in (3000, 8000):
        origins = rng.uniform(lo, hi, (n, 3)).astype(np.float32)
        directions = rng.normal(size=(n, 3)).astype(np.float32)
        assert _visited(tree, origins, directions) >= 8  # the premise: a costly block
        _check_same(tree, origins, directions)


def test_timed_batches_on_a_small_stack():
    # rays that visit fewer than 8 wide nodes, 40,000 of them: the block's first rays go as they
    # are, and a sample of the rest is timed (twice) before the rest goes sorted or not
    knot = procedural.torus_knot(40_000)
    lo, hi = knot.reshape(-1, 3).min(0), knot.reshape(-1, 3).max(0)
    tree = bvhlab.build(knot)
    rng = np.random.default_rng(5)
    origins = rng.uniform(lo, hi, (40_000, 3)).astype(np.float32)
    directions = rng.normal(size=(40_000, 3)).astype(np.float32)
    assert _visited(tree, origins, directions) < 8  # the premise: a timed block
    _check_same(tree, origins, directions)


def test_camera_batches_on_a_small_stack():
    # a camera's rays go through the tree as packets of eight (the packet walk's stack)
    knot = procedural.torus_knot(40_000)
    origins, directions = procedural.camera_rays(knot, 160, 120)
    _check_same(bvhlab.build(knot), origins, directions)
