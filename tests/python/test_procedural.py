"""The bench's scenes unlike Sponza (bench/_peers.scenes) are what their docstrings say."""

import numpy as np

from bvhlab.library import procedural


def test_repeated_row_is_one_knot_shifted_along_x():
    tris = procedural.repeated_row(20_000, copies=20)
    copies = tris.reshape(20, -1, 3, 3)
    for k in range(20):
        np.testing.assert_allclose(copies[k] - np.float32([7.0 * k, 0, 0]), copies[0], atol=1e-4)
    assert len(tris) == 20 * (len(tris) // 20) and 19_000 <= len(tris) <= 21_000


def test_rods_are_long_thin_and_in_their_box():
    tris = procedural.rods(64_000, count=200, sections=8, seed=2)
    per_rod = tris.reshape(200, -1, 3)  # each rod's triangles are consecutive
    for points in per_rod:
        centred = points - points.mean(0)
        s = np.linalg.svd(centred, compute_uv=False)
        extent = np.ptp(centred @ np.linalg.svd(centred)[2][0])
        assert 2.0 - 1e-3 <= extent <= 8.0 + 1e-3  # its length
        assert s[1] / np.sqrt(len(points)) <= 0.02  # radius: the spread across the axis
    assert np.abs(tris.reshape(-1, 3).mean(0)).max() < 1.0 and np.abs(tris).max() < 9.0


def test_vast_room_is_mostly_empty():
    tris = procedural.model_in_vast_room(50_000)
    points = tris.reshape(-1, 3)
    assert np.allclose(points.min(0), -5000) and np.allclose(points.max(0), 5000)
    room = len(procedural.box_room(10_000.0, 8))  # 768 large triangles first, then the knot
    knot = tris[room:].reshape(-1, 3)
    assert np.linalg.norm(knot - np.float32([300, -200, -4990]), axis=1).max() < 10
    assert np.abs(tris[:room]).max(axis=(1, 2)).min() == 5000  # the walls
