"""The watertight triangle test's edge functions that round to 0 (geometry.glsl exact_edge): made
again exactly on every path, as Woop et al. do in double, so that near-degenerate cases neither hit
what a ray passes far from nor let a ray through a mesh. Each case against the exact answer
(fractions) and every traversal against the others, occluded included."""

from fractions import Fraction

import numpy as np
import pytest

import bvhlab


def _hex(rows) -> np.ndarray:
    return np.vectorize(float.fromhex)(np.array(rows, dtype=object)).astype(np.float32)


def _hits(tris, o, d):
    bvh = bvhlab.build(tris)
    out = {}
    for traversal in bvhlab.TRAVERSALS:
        h = bvh.intersect(o, d, traversal=traversal)
        out[traversal] = (h["prim"].tolist(), h["t"].tolist(), bvh.occluded(o, d, traversal=traversal).tolist())
    return out


def _exact_side(tri, o, d) -> list[int]:
    """The signs of the ray's three edge functions about triangle `tri`, exactly (its floats as
    rationals): all of one sign (or 0) where the ray passes through it."""
    o, d = [Fraction(float(x)) for x in o], [Fraction(float(x)) for x in d]
    a, b, c = ([Fraction(float(x)) for x in p] for p in tri)

    def sub(p, q):
        return [p[i] - q[i] for i in range(3)]

    def triple(p, q):  # d · (p × q)
        return (
            d[0] * (p[1] * q[2] - p[2] * q[1]) + d[1] * (p[2] * q[0] - p[0] * q[2]) + d[2] * (p[0] * q[1] - p[1] * q[0])
        )

    values = (triple(sub(b, o), sub(c, o)), triple(sub(c, o), sub(a, o)), triple(sub(a, o), sub(b, o)))
    return [(v > 0) - (v < 0) for v in values]


def test_rays_far_from_a_tiny_triangle_do_not_hit_it():
    """A triangle 1.8e-5 across beside a large one, rays 100-500 units away (a helper's audit):
    1,070 of 200,000 "hit" it, at points ~600 units from it, on every traversal."""
    s = np.float32(1.7864242e-05)
    tris = np.array(
        [[[s, 0, 0], [s, s, 0], [s, 0, s]], [[1000, 1000, 1000], [1000, 1000, 0], [0, 0, 1000]]], np.float32
    )
    rng = np.random.default_rng(0)
    o = (rng.random((50_000, 3)) * 400 + 100).astype(np.float32)
    d = rng.normal(size=(50_000, 3)).astype(np.float32)
    for prims, _, _ in _hits(tris, o, d).values():
        assert prims.count(0) == 0


def test_a_ray_through_a_sliver_hits_the_mesh():
    """A sliver 5.4 long and 2.4e-7 high inside a diamond of three triangles sharing its edges (the
    review's): all three of its edge functions round to 0, and the neighbours' shared ones are exact,
    so a ray through it went through the mesh, hitting none, while only one or two zeros were redone."""
    tris = _hex(
        [
            [
                ["0x1.e18352p-2", "-0x1.b03d72p+1", "-0x1.ef15bap+0"],
                ["-0x1.cd1bcep+0", "-0x1.48bd6cp+2", "-0x1.9fed3ep+2"],
                ["-0x1.c314b6p-2", "-0x1.054676p+2", "-0x1.e1d2c2p+1"],
            ],
            [
                ["-0x1.cd1bcep+0", "-0x1.48bd6cp+2", "-0x1.9fed3ep+2"],
                ["0x1.e18352p-2", "-0x1.b03d72p+1", "-0x1.ef15bap+0"],
                ["-0x1.3be6fep+1", "-0x1.20929ep+1", "-0x1.05d834p+2"],
            ],
            [
                ["0x1.e18352p-2", "-0x1.b03d72p+1", "-0x1.ef15bap+0"],
                ["-0x1.c314b6p-2", "-0x1.054676p+2", "-0x1.e1d2c2p+1"],
                ["0x1.231304p+0", "-0x1.9092d6p+2", "-0x1.15da78p+2"],
            ],
            [
                ["-0x1.c314b6p-2", "-0x1.054676p+2", "-0x1.e1d2c2p+1"],
                ["-0x1.cd1bcep+0", "-0x1.48bd6cp+2", "-0x1.9fed3ep+2"],
                ["0x1.231304p+0", "-0x1.9092d6p+2", "-0x1.15da78p+2"],
            ],
        ]
    )
    o = _hex([["-0x1.1bf904p+1", "-0x1.24c74cp-1", "-0x1.453842p+2"]])
    d = _hex([["0x1.4b8026p-2", "-0x1.e1adfap-1", "0x1.9c42aap-4"]])
    inside = [k for k, tri in enumerate(tris) if len(set(_exact_side(tri, o[0], d[0])) - {0}) < 2]
    assert inside  # the ray passes through the diamond: through one of its triangles, exactly
    results = list(_hits(tris, o, d).values())
    assert all(r == results[0] for r in results), results
    prims, t, occluded = results[0]
    assert prims[0] in range(4) and np.isfinite(t[0]) and occluded == [True]


def test_products_past_float_range_find_the_zeros_on_every_path():
    """Two triangles ~1e11 out (inside the ±2^40 range): an edge function of 0 beside two whose
    product overflows; the wide walks' test for zeros by a product of the three missed it (the
    review's: stack and stackless hit triangle 0, the wide walk triangle 1). The exact answer: the
    ray passes through neither."""
    tris = _hex(
        [
            [
                ["-0x1.211724p+37", "0x1.dd5d42p+36", "0x1.acc9c4p+37"],
                ["-0x1.b98c3cp+35", "0x1.6c0162p+37", "0x1.acc9c4p+37"],
                ["-0x1.211724p+37", "0x1.a0f0b4p+37", "0x1.2fbeecp+38"],
            ],
            [
                ["-0x1.b98c3cp+35", "0x1.6c0162p+37", "0x1.acc9c4p+37"],
                ["-0x1.211724p+37", "0x1.dd5d42p+36", "0x1.acc9c4p+37"],
                ["-0x1.211724p+37", "0x1.dfd46p+34", "0x1.f42b5ep+36"],
            ],
        ]
    )
    o = _hex([["0x1.1cc512p+39", "0x1.9a083p+37", "0x1.4f0188p+35"]])
    d = _hex([["-0x1.6afeeep-1", "-0x1.6d4p-11", "0x1.5e4576p-2"]])
    for tri in tris:
        assert len(set(_exact_side(tri, o[0], d[0])) - {0}) == 2
    results = list(_hits(tris, o, d).values())
    assert all(r == results[0] for r in results), results
    assert results[0][0] == [-1]


@pytest.mark.parametrize("scale", [1e-3, 1.0, 1e6, 1e10])
def test_every_traversal_agrees_on_near_degenerate_triangles(scale):
    """Slivers (a vertex half an ulp off the opposite edge), triangles of one-ulp sides and tiny
    triangles far from the rays, at several scales: every traversal gives the same hits."""
    rng = np.random.default_rng(int(np.log10(scale) + 10))
    n = 3000
    a = rng.normal(size=(n, 3)) * scale
    b = a + rng.normal(size=(n, 3)) * scale
    c = np.where((np.arange(n) % 3 == 0)[:, None], (a + b) / 2 + 1e-7 * scale, a + np.spacing(a.astype(np.float32)) * 3)
    c[1::3] = a[1::3] + rng.normal(size=(len(a[1::3]), 3)) * scale * 1e-6
    tris = np.stack([a, b, c], 1).astype(np.float32)
    o = (rng.normal(size=(4000, 3)) * scale * 4).astype(np.float32)
    d = (tris[rng.integers(0, n, 4000)].mean(1) - o).astype(np.float32)
    results = list(_hits(tris, o, d).values())
    assert all(r == results[0] for r in results)
