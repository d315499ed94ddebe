"""Bvh.occluded and InstancedBvh.occluded (the any-hit query, issue 36) against the closest hit:
for every ray, occluded == (intersect's t < tmax), on every traversal, with tmax at, just after and
just before each ray's hit (a hit at exactly tmax does not count, as in intersect); hostile
arguments raise ValueError (TypeError for a wrong type); threads give the same answers."""

import threading

import numpy as np
import pytest
from test_instanced_scene import _rays, _transform

import bvhlab
from bvhlab import ray_query
from bvhlab.library import procedural


def _tmax_cases(t: np.ndarray, seed: int) -> list[np.ndarray]:
    """Per-ray tmax arrays from each ray's closest t (inf on a miss): the hit's t itself (not
    occluded), the next float after it (occluded), the one before, half of it, random ones."""
    finite = np.where(np.isfinite(t), t, np.float32(7.0))
    rng = np.random.default_rng(seed)
    return [
        finite,
        np.nextafter(finite, np.float32(np.inf)),
        np.nextafter(finite, np.float32(0)),
        finite * np.float32(0.5),
        rng.uniform(0, 3, len(t)).astype(np.float32),
        np.full(len(t), np.inf, np.float32),
    ]


def _expect_occluded_is_closest_before_tmax(tree, o, d, traversal, tmin=0.0):
    t = tree.intersect(o, d, tmin=tmin, traversal=traversal)["t"]
    assert np.isfinite(t).mean() > 0.1, "the rays must hit something to test anything"
    for k, tmax in enumerate(_tmax_cases(t, 3)):
        got = tree.occluded(o, d, tmax, tmin=tmin, traversal=traversal)
        assert got.dtype == np.bool_ and got.shape == (len(o),)
        np.testing.assert_array_equal(got, t < tmax, err_msg=f"tmax case {k}")
    for tmax in (0.0, 0.3, 1.0, np.inf):  # a scalar tmax
        np.testing.assert_array_equal(tree.occluded(o, d, tmax, tmin=tmin, traversal=traversal), t < tmax)


@pytest.mark.parametrize("traversal", bvhlab.TRAVERSALS)
def test_equals_closest_hit_before_tmax(small_scene, traversal):
    tris, spheres = small_scene
    for leaf in (1, 4):
        bvh = bvhlab.build(tris, spheres, max_leaf_size=leaf)
        o, d = procedural.random_rays(tris, 3000, seed=5)
        d[::7, 1] = 0  # axis-parallel components
        d[::5] *= 3.7  # unnormalised
        _expect_occluded_is_closest_before_tmax(bvh, o, d, traversal)
        _expect_occluded_is_closest_before_tmax(bvh, o, d, traversal, tmin=0.2)


@pytest.mark.parametrize("traversal", bvhlab.TRAVERSALS)
def test_equals_closest_hit_on_rays_through_vertices_and_edges(traversal):
    mesh = procedural.torus_knot(4000)
    bvh = bvhlab.build(mesh)
    rng = np.random.default_rng(2)
    lo, hi = mesh.reshape(-1, 3).min(0), mesh.reshape(-1, 3).max(0)
    tri = mesh[rng.integers(0, len(mesh), 3000)]
    targets = np.concatenate([tri[:1000, 0], (tri[1000:2000, 0] + tri[1000:2000, 1]) / 2, tri[2000:, 2]])
    o = rng.uniform(lo - 1, hi + 1, (3000, 3)).astype(np.float32)
    d = np.ascontiguousarray(targets - o, np.float32)
    _expect_occluded_is_closest_before_tmax(bvh, o, d, traversal)


@pytest.fixture(scope="module")
def rotated_instances():
    """A cloud and a knot, instanced rotated, scaled non-uniformly, mirrored and overlapping."""
    transforms = np.stack(
        [
            _transform(0.0, (0, 0, 1), (1, 1, 1), (0, 0, 0)),
            _transform(0.6, (1, 2, 3), (2.0, 0.5, 1.3), (3, 0, 0)),
            _transform(1.1, (0, 1, 0), (-1, 1, 1), (0, 3, 0)),
            _transform(2.0, (1, 1, 0), (-0.7, -1.5, 2.5), (3, 3, 1)),
            _transform(0.3, (0, 0, 1), (1, 1, 1), (0.2, 0.1, 0)),
        ]
    )
    return bvhlab.Scene(
        triangles=procedural.random_triangles(300, size=0.15, seed=4),
        meshes=[procedural.torus_knot(2000)],
        instance_mesh=np.array([0, 1, 0, 1, 1]),
        instance_transforms=transforms,
    )


@pytest.mark.parametrize("traversal", bvhlab.TRAVERSALS)
def test_instanced_equals_closest_hit_before_tmax(rotated_instances, traversal):
    tree = bvhlab.build(rotated_instances)
    assert isinstance(tree, bvhlab.InstancedBvh)
    o, d = _rays(rotated_instances, 4000, 7)
    _expect_occluded_is_closest_before_tmax(tree, o, d, traversal)


@pytest.fixture(scope="module")
def tree_and_rays():
    tris = procedural.random_triangles(500, size=0.1, seed=3)
    o, d = procedural.random_rays(tris, 4, seed=1)
    return bvhlab.build(tris), o, d


@pytest.mark.parametrize(
    "tmax, error, match",
    [
        (float("nan"), ValueError, "tmax must be a number, got NaN"),
        (-1.0, ValueError, "tmax must be at least 0, got -1.0"),
        (np.array([1, np.nan, 1, 1], np.float32), ValueError, "ray 1: tmax must be a number >= 0"),
        (np.array([1, 1, 1, -0.5], np.float32), ValueError, "ray 3: tmax must be a number >= 0"),
        (np.ones(3, np.float32), ValueError, "tmax has 3 entries for 4 rays"),
        (np.ones((4, 1), np.float32), ValueError, "tmax must have shape"),
        (np.ones(4), TypeError, "tmax must have dtype float32"),
        ("1", TypeError, "tmax must be a number"),
        (None, TypeError, "tmax must be a number"),
    ],
)
def test_bad_tmax(tree_and_rays, tmax, error, match):
    bvh, o, d = tree_and_rays
    with pytest.raises(error, match=match):
        bvh.occluded(o, d, tmax)


def test_a_tmax_of_no_dimensions_is_a_number(tree_and_rays):
    """np.array(2.0) said "tmax must have shape (N,), got ()" where np.float32(2.0) was taken."""
    bvh, o, d = tree_and_rays
    for tmax in (0.5, 100.0):
        expected = bvh.occluded(o, d, tmax)
        np.testing.assert_array_equal(bvh.occluded(o, d, np.array(tmax, np.float32)), expected)
        np.testing.assert_array_equal(bvh.occluded(o, d, np.array(tmax)), expected)
    with pytest.raises(ValueError, match="tmax must be at least 0"):
        bvh.occluded(o, d, np.array(-1.0))
    for key in ("t", "prim"):  # intersect's tmin and tmax alike
        np.testing.assert_array_equal(
            bvh.intersect(o, d, tmin=np.array(0.25), tmax=np.array(50.0, np.float32))[key],
            bvh.intersect(o, d, tmin=0.25, tmax=50.0)[key],
        )
    with pytest.raises(TypeError, match="tmax must be a number"):  # a masked array is not taken as one
        bvh.occluded(o, d, np.ma.masked_array(2.0, mask=True))


def test_an_integer_beyond_float_is_infinite(tree_and_rays):
    """10**400 is read as 1e400 is, infinity (it raised OverflowError: int too large to convert to
    float, naming no argument: a helper's audit); -10**400 is refused naming tmax."""
    bvh, o, d = tree_and_rays
    np.testing.assert_array_equal(bvh.occluded(o, d, 10**400), bvh.occluded(o, d, np.inf))
    np.testing.assert_array_equal(bvh.intersect(o, d, tmax=10**400)["t"], bvh.intersect(o, d)["t"])
    with pytest.raises(ValueError, match="tmax must be at least 0, got -inf"):
        bvh.occluded(o, d, -(10**400))
    assert np.isinf(bvh.intersect(o, d, tmin=10**400)["t"]).all()  # as tmin=inf: nothing after it


def test_bad_rays_as_for_intersect(tree_and_rays):
    bvh, o, d = tree_and_rays
    with pytest.raises(ValueError, match="differ in length"):
        bvh.occluded(o, d[:3])
    with pytest.raises(ValueError, match="must have shape"):
        bvh.occluded(o[:, :2].copy(), d)
    with pytest.raises(TypeError, match="float32"):
        bvh.occluded(o.astype(np.float64), d)
    bad = o.copy()
    bad[2, 1] = np.nan
    with pytest.raises(ValueError, match="ray 2: origin and direction must be finite"):
        bvh.occluded(bad, d)
    with pytest.raises(ValueError, match="ray 1"):
        bvh.occluded(o, np.array([[1, 0, 0], [0, 0, 0], [1, 0, 0], [1, 0, 0]], np.float32))
    with pytest.raises(ValueError, match="traversal"):
        bvh.occluded(o, d, traversal="bfs")
    with pytest.raises(ValueError, match="tmin"):
        bvh.occluded(o, d, tmin=float("nan"))


def test_threads_give_the_same_answers(knot_mesh):
    bvh = bvhlab.build(knot_mesh)
    o, d = procedural.random_rays(knot_mesh, 40000, seed=9)
    tmax = np.random.default_rng(1).uniform(0, 3.0, len(o)).astype(np.float32)
    want = bvh.intersect(o, d, threads=1)["t"] < tmax
    assert 0.1 < want.mean() < 0.9
    for threads in (1, 2, 5):
        np.testing.assert_array_equal(bvh.occluded(o, d, tmax, threads=threads), want)
    got, errors = {}, []

    def query(k):
        try:
            got[k] = bvh.occluded(o, d, tmax, traversal=bvhlab.TRAVERSALS[k % len(bvhlab.TRAVERSALS)])
        except Exception as e:  # noqa: BLE001 - reported below
            errors.append(e)

    threads = [threading.Thread(target=query, args=(k,)) for k in range(6)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert not errors
    for k in range(6):
        np.testing.assert_array_equal(got[k], want)


@pytest.mark.parametrize("two_level", [False, True])
@pytest.mark.parametrize("tmax, match", [(-1.0, "tmax must be at least 0, got -1.0"), (float("nan"), "got NaN")])
def test_intersect_refuses_the_tmax_occluded_refuses(tree_and_rays, two_level, tmax, match):
    """A negative tmax was answered by misses in `intersect` (an empty interval) where `occluded`
    refused it: both refuse it now, on flat and two-level trees, through Python and the core, and
    so does the inspector's trace_ray."""
    bvh, o, d = tree_and_rays
    if two_level:
        knot = procedural.torus_knot(200)
        move = np.array([[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 2]], np.float32)
        bvh = bvhlab.build(
            bvhlab.Scene(
                meshes=[knot],
                instance_mesh=np.array([1, 1]),  # the knot twice (mesh 0, the scene's own, is empty)
                instance_transforms=np.stack([np.eye(3, 4, dtype=np.float32), move]),
            )
        )
        assert isinstance(bvh, bvhlab.InstancedBvh)
        o, d = _rays(bvhlab.Scene(meshes=[knot]), 64, 3)  # at the knot where its first instance is
        assert np.isfinite(bvh.intersect(o, d)["t"]).sum() > 10
    for query in (bvh.intersect, bvh.occluded):
        with pytest.raises(ValueError, match=match):
            query(o, d, tmax=tmax)
    n = len(o)  # the core's own check, under Python's: its arrays as run_ray_query makes them
    out = [np.empty(n, t) if k != "nodes_visited" else None for k, t in ray_query.HIT_FIELDS.items()]
    out += [np.empty(n, np.int32)] * two_level  # the instance of each hit
    with pytest.raises(ValueError, match="tmax must be a number >= 0"):
        bvh._core.intersect(o, d, 0.0, tmax, "wide", 1, *out)
    if not two_level:
        with pytest.raises(ValueError, match=match):
            bvh.trace_ray(o[0], d[0], tmax=tmax)
