"""Issue 8.5: huge coordinates were accepted and never hit (a 1e13 triangle, a 2e19 sphere, a ray
direction of length 1e-28). Now geometry outside ±MAX_COORDINATE is refused naming the primitive,
everything inside is hit as a float64 brute force says, and any direction whose largest component
lies in [MIN_DIRECTION, MAX_DIRECTION] works (core_cpp/include/bvhlab/coordinate_range.h)."""

import numpy as np
import pytest
from oracles import brute_force

import bvhlab
from bvhlab.bvh import MAX_DIRECTION, MIN_DIRECTION, MIN_RADIUS
from bvhlab.library import procedural
from bvhlab.scene import MAX_COORDINATE

L = MAX_COORDINATE


def test_the_range_is_2_to_the_40():
    assert L == 2.0**40 and MIN_DIRECTION == 2.0**-80 and MAX_DIRECTION == 2.0**80 and MIN_RADIUS == 2.0**-60


@pytest.mark.parametrize("size", [1e13, 1e15, 3.4e38])
def test_a_triangle_beyond_the_range_is_refused_by_name(size):
    tris = procedural.random_triangles(10, seed=1)
    tris[6] = [[-size, -size, 0], [size, -size, 0], [0, size, 0]]
    with pytest.raises(ValueError, match=r"triangle 6 has a vertex coordinate outside the supported range"):
        bvhlab.build(tris)
    with pytest.raises(ValueError, match="triangle 6"):
        bvhlab.Scene(triangles=tris)


@pytest.mark.parametrize("centre, radius", [(0, 2e19), (0, 1.2e12), (1.0e12, 1e11)])
def test_a_sphere_reaching_beyond_the_range_is_refused_by_name(centre, radius):
    spheres = np.array([[0, 0, 0, 1], [0, 0, 0, 2], [centre, 0, 0, radius]], np.float32)
    with pytest.raises(ValueError, match=r"sphere 2 \(centre ± radius\) reaches outside the supported range"):
        bvhlab.build(np.zeros((0, 3, 3), np.float32), spheres)


def test_refit_refuses_geometry_moved_beyond_the_range():
    tris = procedural.random_triangles(50, seed=1)
    bvh = bvhlab.build(tris)
    moved = tris.copy()
    moved[3, 1, 2] = 2e12
    with pytest.raises(ValueError, match="triangle 3"):
        bvh.refit(moved)
    assert bvh.revision == 0  # the tree is unchanged


def test_rays_starting_beyond_the_range_are_refused_by_name():
    bvh = bvhlab.build(procedural.random_triangles(50, seed=1))
    o = np.zeros((3, 3), np.float32)
    o[1, 0] = -1.2e12
    with pytest.raises(ValueError, match=r"ray 1 starts outside the supported coordinate range"):
        bvh.intersect(o, np.ones((3, 3), np.float32))


@pytest.mark.parametrize("largest", [0.0, 1e-30, 2.0**-81, 2.0**81, 1e30])
def test_directions_beyond_the_range_are_refused_by_name(largest):
    bvh = bvhlab.build(procedural.random_triangles(50, seed=1))
    d = np.ones((3, 3), np.float32)
    d[2] = [largest, largest / 2, 0]
    with pytest.raises(ValueError, match=r"ray 2: the largest \|component\| of a direction must be in"):
        bvh.intersect(np.zeros((3, 3), np.float32), d)


def _giant_scene(rng, n_tris=300, n_spheres=40):
    """Triangles and spheres spread over the whole range, some as large as it (corners at ±L)."""
    tris = rng.uniform(-L, L, (n_tris, 3, 3)).astype(np.float32)
    tris[:20] = rng.choice([-L, L], (20, 3, 3)).astype(np.float32)  # corner to corner
    tris[20:40] = (rng.uniform(-1, 1, (20, 3, 3)) * L / 2**20 + rng.uniform(-L / 2, L / 2, (20, 1, 3))).astype(
        np.float32
    )
    centres = rng.uniform(-L / 2, L / 2, (n_spheres, 3))
    radii = rng.uniform(L / 64, L / 2, n_spheres)
    spheres = np.column_stack([centres, radii]).astype(np.float32)
    return np.ascontiguousarray(tris), spheres


def test_geometry_as_large_as_the_range_is_hit_as_at_unit_scale():
    """At the edge of the range nothing may overflow. Every test is homogeneous in the coordinates,
    so the same scene and rays scaled by 2^-40 (exactly) must give bit for bit the same hits, t
    scaled back; and both agree with a float64 brute force up to float32 precision."""
    rng = np.random.default_rng(8)
    tris, spheres = _giant_scene(rng)
    n = 3000
    o = rng.choice([-1, 1], (n, 3)) * rng.uniform(0.5, 1.0, (n, 3)) * L  # far corners: |o - v| up to 2L
    d = rng.uniform(-L / 2, L / 2, (n, 3)) - o
    o, d = o.astype(np.float32), (d / np.abs(d).max(1, keepdims=True)).astype(np.float32)
    unit = np.float32(2.0**-40)
    small = bvhlab.build(tris * unit, spheres * unit)
    big = bvhlab.build(tris, spheres)
    want_t, want_id, want_kind = brute_force(tris, spheres, o, d)
    assert np.isfinite(want_t).mean() > 0.5
    for traversal in bvhlab.TRAVERSALS:
        got = big.intersect(o, d, traversal=traversal)
        at_unit = small.intersect(o * unit, d, traversal=traversal)
        for key in ("prim", "kind", "u", "v"):
            np.testing.assert_array_equal(got[key], at_unit[key], err_msg=f"{traversal} {key}")
        np.testing.assert_array_equal(got["t"] * unit, at_unit["t"])
        same = np.isfinite(got["t"]) == np.isfinite(want_t)
        assert same.mean() >= 0.999, f"{traversal}: {np.count_nonzero(~same)} rays disagree on hit or miss"
        both = np.isfinite(got["t"]) & np.isfinite(want_t)
        close = np.abs(got["t"][both] - want_t[both]) <= 1e-4 * want_t[both]
        assert close.mean() >= 0.995
        # another primitive only at the same distance (the cube-corner triangles share planes, some
        # are one triangle with its vertices in another order): equal up to the rounding of the
        # coordinates themselves, a few float32 spacings at L (2^-23 L), which is more than 1e-4 t
        # for a hit near the origin (the watertight test's t, Woop et al. 2013, is a sum of
        # vertex distances of size L, as Möller–Trumbore's is)
        other = (got["prim"][both] != want_id[both]) | (got["kind"][both] != want_kind[both])
        same_place = np.abs(got["t"][both] - want_t[both]) <= 1e-4 * want_t[both] + 4 * 2.0**-23 * L
        assert np.all(same_place[other]), (
            f"{traversal}: {np.count_nonzero(other & ~same_place)} rays hit another primitive"
        )


#: Direction scales: exact powers of two (results must be bit-identical after rescaling t) and
#: arbitrary ones (compared with float64), down to the ends of the allowed range.
POWERS = [2.0**-79, 2.0**-40, 2.0**-1, 2.0**1, 2.0**30, 2.0**79]
OTHERS = [2e-24, 1e-20, 3.7e-13, 1e-3, 7.3, 1e9, 1e20, 1e24]


@pytest.fixture(scope="module")
def scene_and_rays():
    tris, spheres = procedural.random_triangles(500, size=0.2, seed=4), procedural.random_spheres(50, 0.05, seed=5)
    o, d = procedural.random_rays(tris, 4000, seed=6)
    return tris, spheres, o, d


@pytest.mark.parametrize("scale", POWERS)
def test_power_of_two_directions_give_bit_identical_hits(scene_and_rays, scale):
    tris, spheres, o, d = scene_and_rays
    bvh = bvhlab.build(tris, spheres)
    unit = bvh.intersect(o, d)
    scaled = bvh.intersect(o, (d * np.float32(scale)).astype(np.float32))
    for key in ("prim", "kind", "u", "v"):
        np.testing.assert_array_equal(scaled[key], unit[key], err_msg=key)
    np.testing.assert_array_equal(scaled["t"] * np.float32(scale), unit["t"])


@pytest.mark.parametrize("scale", OTHERS)
@pytest.mark.parametrize("traversal", bvhlab.TRAVERSALS)
def test_any_direction_length_is_hit_as_float64_says(scene_and_rays, scale, traversal):
    """The sphere at |d| = 1e-20 was 4e-6 off (|d|² subnormal), and |d| ≤ 1e-28 missed everything."""
    tris, spheres, o, d = scene_and_rays
    d = (d.astype(np.float64) * scale).astype(np.float32)
    got = bvhlab.build(tris, spheres).intersect(o, d, traversal=traversal)
    want_t, want_id, want_kind = brute_force(tris, spheres, o, d)
    hit = np.isfinite(want_t)
    assert hit.mean() > 0.2
    assert np.array_equal(np.isfinite(got["t"]), hit)
    np.testing.assert_allclose(got["t"][hit], want_t[hit], rtol=1e-4)
    assert np.all((got["prim"][hit] == want_id[hit]) & (got["kind"][hit] == want_kind[hit]))


embreex = pytest.importorskip("embreex", reason="embreex is installed by make test")


@pytest.mark.parametrize("scale", [1e-6, 1e-3, 1e3, 1e6])
def test_scaled_directions_agree_with_embree(knot_mesh, scale):
    from test_intersect import embree_hits

    o, d = procedural.random_rays(knot_mesh, 20000, seed=9)
    d = (d * scale).astype(np.float32)
    want_t, want_id = embree_hits(knot_mesh, o, d)
    got = bvhlab.build(knot_mesh).intersect(o, d)
    same = np.isfinite(got["t"]) == np.isfinite(want_t)
    assert same.mean() >= 0.9999
    both = np.isfinite(got["t"]) & np.isfinite(want_t)
    assert np.mean(np.abs(got["t"][both] - want_t[both]) <= 1e-4 * want_t[both]) >= 0.9999
