"""Polygons of mesh files into triangles (bvhlab.library.polygons): holes bridged, combs and random
simple polygons covered exactly (areas by the shoelace formula), degenerate corners, the ear grid
against a test of every corner, and polygons of one size at once equal to one by one (split from
test_mesh_readers.py)."""

import numpy as np
import pytest
from test_mesh_readers import area, load

from bvhlab.library import polygons


def test_a_polygon_bridged_to_its_hole_keeps_the_hole(tmp_path):
    """A square with a square hole, joined by a bridge whose corners repeat (a "keyhole"): area
    16 - 4 = 12. Ear clipping refused ears at the repeated corners and fell back to a fan (24)."""
    outer, inner = [(0, 0), (4, 0), (4, 4), (0, 4)], [(1, 1), (1, 3), (3, 3), (3, 1)]
    ring = outer + [outer[0], inner[0]] + inner[1:] + [inner[0]]
    vertices = "".join(f"v {x} {y} 0\n" for x, y in ring)
    t = load(tmp_path, "keyhole.obj", vertices + "f " + " ".join(str(i + 1) for i in range(len(ring))) + "\n")
    assert area(t) == pytest.approx(12.0)


def shoelace(xy) -> float:
    x, y = np.asarray(xy, np.float64).T
    return 0.5 * abs(float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1))))


def test_a_comb_of_4002_corners_keeps_its_shape(tmp_path):
    """A polygon of 2,000 teeth (half its corners reflex), as a long outline in a CAD export is:
    n − 2 triangles of its own area. Ear clipping by whole scans took 7 s for 2,002 corners and
    about an hour for 16,002 (O(n³)); the kept ear tests take 0.35 s and 6 s."""
    teeth = 2000
    ring = [(0.0, -1.0), (float(teeth), -1.0)]
    for i in range(teeth - 1, -1, -1):
        ring += [(i + 1.0, 1.0), (i + 0.5, 0.0)]
    vertices = "".join(f"v {x} {y} 0\n" for x, y in ring)
    t = load(tmp_path, "comb.obj", vertices + "f " + " ".join(str(i + 1) for i in range(len(ring))) + "\n")
    assert len(t) == len(ring) - 2
    assert area(t) == pytest.approx(shoelace(ring), rel=1e-12)


@pytest.mark.parametrize("seed", range(40))
def test_simple_polygons_are_covered_exactly(tmp_path, seed):
    """Random star-shaped polygons (simple, concave, some with radii rounded to tenths), either
    winding: triangles of their corners whose areas sum to the polygon's."""
    rng = np.random.default_rng(seed)
    n = int(rng.integers(5, 90))
    angle, radius = np.sort(rng.uniform(0, 2 * np.pi, n)), rng.uniform(0.2, 1.0, n)
    if seed % 3 == 0:
        radius = np.round(radius, 1)
    ring = np.stack([radius * np.cos(angle), radius * np.sin(angle)], 1)[:: 1 if seed % 2 else -1]
    vertices = "".join(f"v {x!r} {y!r} 0\n" for x, y in ring)
    t = load(tmp_path, "star.obj", vertices + "f " + " ".join(str(i + 1) for i in range(n)) + "\n")
    assert len(t) == n - 2
    assert area(t) == pytest.approx(shoelace(ring), rel=1e-6)  # float32 positions


@pytest.mark.parametrize(
    "ring",
    [
        # a concave hexagon with a corner in the middle of a straight edge (flat: 180°)
        [(0, 0), (2, 0), (4, 0), (4, 2), (2, 1), (0, 2)],
        # the same with a corner repeated (a zero-length edge)
        [(0, 0), (2, 0), (2, 0), (4, 0), (4, 2), (2, 1), (0, 2)],
        # clockwise
        [(0, 2), (2, 1), (4, 2), (4, 0), (2, 0), (0, 0)],
        # a comb whose teeth's tips lie on one line with the base's corner
        [(0, 0), (6, 0), (6, 3), (5, 1), (4, 3), (3, 1), (2, 3), (1, 1), (0, 3)],
    ],
)
def test_degenerate_corners_keep_the_area(tmp_path, ring):
    """Flat, repeated and clockwise corners: the polygon's area, no triangle outside it."""
    vertices = "".join(f"v {x} {y} 0\n" for x, y in ring)
    t = load(tmp_path, "odd.obj", vertices + "f " + " ".join(str(i + 1) for i in range(len(ring))) + "\n")
    assert len(t) == len(ring) - 2
    assert area(t) == pytest.approx(shoelace(ring), rel=1e-6)


def _every_corner(self, x0, y0, x1, y1):
    """polygons._Blockers.near without the grid: every corner that may block, for the reference."""
    return list(range(len(self.xy)))


def test_the_ear_grid_gives_the_triangles_of_a_test_of_every_corner(monkeypatch):
    """The grid that made a 32,000-corner outline 3× faster only skips corners that cannot lie in
    an ear: the same triangles as testing every blocking corner, on random simple, clockwise,
    self-intersecting and rounded polygons in every rotation of their corners, and on the review's
    polygon, whose corner 2^-53 off an ear's box tested inside the ear by the doubles' sign (the
    tests are exact now). Every polygon through _ear_clip (_SMALL 3): those of up to 32 corners
    went to _ear_clip_small, which has no grid (a review: the test was vacuous for them)."""
    monkeypatch.setattr(polygons, "_SMALL", 3)
    rng = np.random.default_rng(7)
    polygons_ = [np.array([(0, 0), (1, 2**-20), (1, 1), (-1, 1), (-1, -1), (-0.5, -1), (-(2**-53), 0)])]
    for trial in range(120):
        n = int(rng.integers(5, 120))
        angle = np.sort(rng.uniform(0, 2 * np.pi, n))
        p = np.stack([np.cos(angle), np.sin(angle)], 1) * rng.uniform(0.2, 1, (n, 1))
        if trial % 4 == 1:
            p = np.round(p * 4) / 4  # repeated and collinear corners
        if trial % 4 == 2:
            p = p[::-1]  # clockwise
        if trial % 4 == 3:
            p = p[rng.permutation(n)]  # self-intersecting
        polygons_.append(p * 10.0 ** rng.integers(-6, 7))
    for p in polygons_:
        xy = np.concatenate([p, np.zeros((len(p), 1))], 1)
        for start in range(0, len(p), max(1, len(p) // 4)):
            corners = list(np.roll(np.arange(len(p)), -start))
            got = polygons.triangulate(corners, xy)
            with monkeypatch.context() as m:
                m.setattr(polygons._Blockers, "near", _every_corner)
                assert got == polygons.triangulate(corners, xy)


@pytest.mark.parametrize("n", [5, 6, 9, 17, 32, 33])
def test_polygons_of_one_size_at_once_are_triangulated_one_by_one(n):
    """triangulate_all's polygons of more than four corners: the convex ones fanned in numpy at
    once, the rest one by one (200,000 hexagons took 23.7 s one by one: a helper's probe), those of
    at most 32 corners by the ear clipping in Python floats (150,000 concave hexagons took 49 s
    through numpy's: a probe); the triangles equal `triangulate`'s polygon by polygon, for convex,
    concave, clockwise, slightly non-planar, rounded (repeated and collinear corners),
    self-intersecting and degenerate (all corners on a line) polygons."""
    rng = np.random.default_rng(n)
    count = 600
    angles = np.sort(rng.uniform(0, 2 * np.pi, (count, n)), axis=1)
    radii = np.where(np.arange(count)[:, None] < count // 2, 1.0, rng.uniform(0.2, 1.0, (count, n)))
    xyz = np.stack([radii * np.cos(angles), radii * np.sin(angles), rng.normal(0, 1e-3, (count, n))], -1)
    xyz[300:400] = np.round(xyz[300:400] * 4) / 4  # repeated and collinear corners
    xyz[400:450] = xyz[400:450, rng.permutation(n)]  # self-intersecting
    xyz[-1] = np.stack([np.linspace(0, 1, n)] * 3, -1)  # every corner on one line: no normal
    # convex, corner 2 the midpoint of corners 1 and 3 (flat), on a sloped plane: the two paths'
    # turns differed in their last bits and one fanned what the other clipped (the review's)
    flat = [(14.7, 6.3, 0.6299999999999999), (14.0, 7.7, 1.959999999999999), (6.55, 11.85, 7.515000000000001)]
    flat += [(-0.9, 16.0, 13.07), (-1.5, -15.9, -12.270000000000001)]
    flat += [(10.2, -12.4, -12.980000000000002)] * (n - 5)
    xyz[-2] = np.array(flat)[:n]
    positions = xyz.reshape(-1, 3)
    faces = np.arange(count * n).reshape(count, n)
    faces[::5] = faces[::5, ::-1]
    one_by_one = [t for f in faces for t in polygons.triangulate(list(f), positions)]
    assert np.array_equal(polygons.triangulate_all(list(faces), positions), np.array(one_by_one))


def test_integer_positions_are_clipped_as_floats():
    """The review's: the Python-float clipping took integer positions as exact integers where the
    numpy clipping takes them as doubles (corners near 2^53): other triangles."""
    big = 2**53
    ring = [[0, 2, 0], [big + 3, 1, 0], [big + 1, -3, 0], [-2, -3, 0], [big, -3, 0], [big + 1, 0, 0]]
    positions = np.array(ring, np.int64)
    faces = [list(range(6))]
    assert polygons.triangulate_all(faces, positions).tolist() == [
        list(t) for t in polygons.triangulate(faces[0], positions)
    ]


@pytest.mark.parametrize("block", [1, 7, 1 << 16])
def test_polygons_laid_end_to_end_are_those_of_triangulate_all(monkeypatch, block):
    """triangulate_runs (an OBJ's faces as one index array and their sizes: no Python object a
    polygon; 490,000 quads peaked at 710 MiB through a list of them, 375 since, with _BLOCK) gives
    triangulate_all's triangles in its order: triangles, then quads (convex and with a reflex
    corner), then larger polygons, concave among them; points and edges give none. The faces go
    through the arithmetic `block` at a time (_BLOCK), across the blocks' ends."""
    monkeypatch.setattr(polygons, "_BLOCK", block)
    rng = np.random.default_rng(3)
    positions = rng.normal(size=(400, 3))
    positions[:, 2] *= 1e-3  # near a plane: polygons with reflex corners
    sizes = rng.choice([1, 2, 3, 4, 4, 5, 6, 9], size=150)
    corners = [rng.choice(len(positions), size=n, replace=False) for n in sizes]
    expected = polygons.triangulate_all([c for c in corners if len(c) >= 3], positions)
    got = polygons.triangulate_runs(np.concatenate(corners).astype(np.int64), sizes, positions)
    assert np.array_equal(got, expected) and len(expected) == sum(n - 2 for n in sizes if n >= 3)
