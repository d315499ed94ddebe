"""Bvh.node_data (issue 35): every node's figures against answers worked out here independently:
counts and SAH sums from the node array, EPO from a clip of every triangle by every box done in
the triangle's own plane (half-planes in barycentric coordinates, not the core's clipping)."""

import dataclasses
import itertools

import numpy as np
import pytest

import bvhlab
from bvhlab.library import procedural


def _children(bvh):
    nodes = bvh.nodes
    leaf = bvh.is_leaf
    return [() if leaf[i] else (i + 1, int(nodes["index"][i])) for i in range(len(nodes))]


def _subtree_slots(bvh):
    """The leaf slots under each node, by walking the children (not the depth-first ranges)."""
    nodes, children = bvh.nodes, _children(bvh)
    slots = [None] * len(nodes)
    for i in reversed(range(len(nodes))):
        if children[i]:
            slots[i] = slots[children[i][0]] | slots[children[i][1]]
        else:
            first, count = int(nodes["index"][i]), int(nodes["info"][i])
            slots[i] = set(range(first, first + count))
    return slots


def _area_in_box(tri, lo, hi):
    """Area of triangle ∩ box: the polygon {(u, v): u, v >= 0, u + v <= 1, lo <= p(u, v) <= hi} in
    the triangle's barycentric plane, from the vertices of its half-planes' arrangement."""
    v0, e1, e2 = tri[0], tri[1] - tri[0], tri[2] - tri[0]
    rows = [(-1.0, 0.0, 0.0), (0.0, -1.0, 0.0), (1.0, 1.0, 1.0)]  # a·u + b·v <= c
    for k in range(3):
        rows.append((e1[k], e2[k], hi[k] - v0[k]))
        rows.append((-e1[k], -e2[k], v0[k] - lo[k]))
    rows = np.array(rows)
    points = []
    for r, s in itertools.combinations(rows, 2):
        m = np.array([r[:2], s[:2]])
        if abs(np.linalg.det(m)) < 1e-300:
            continue
        p = np.linalg.solve(m, [r[2], s[2]])
        if np.all(rows[:, :2] @ p <= rows[:, 2] + 1e-12):
            points.append(p)
    if len(points) < 3:
        return 0.0
    pts = np.array(points)
    c = pts.mean(0)
    pts = pts[np.argsort(np.arctan2(pts[:, 1] - c[1], pts[:, 0] - c[0]))]
    x, y = pts[:, 0], pts[:, 1]
    uv_area = 0.5 * abs(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))
    return uv_area * np.linalg.norm(np.cross(e1, e2))


@pytest.fixture(scope="module")
def small_tree():
    tris = procedural.random_triangles(70, size=0.3, seed=5)
    return tris, bvhlab.build(tris, method="sah", max_leaf_size=4)


def test_sah_shares_sum_to_the_sah_cost(small_tree, knot_mesh):
    for bvh in (small_tree[1], bvhlab.build(knot_mesh, method="median")):
        d = bvh.node_data()
        sah = bvh.stats["sah_cost"]
        assert d.sah_term.sum() == pytest.approx(sah, rel=1e-12)
        assert d.sah_cost == pytest.approx(sah, rel=1e-12)
        assert d.subtree_sah[0] == pytest.approx(sah, rel=1e-12) and d.sah_share[0] == pytest.approx(1.0)
        internal = d.left >= 0
        own_plus_children = d.sah_term[internal] + d.subtree_sah[d.left[internal]] + d.subtree_sah[d.right[internal]]
        np.testing.assert_allclose(d.subtree_sah[internal], own_plus_children, rtol=1e-12)
        # the leaves' shares partition the tree's cost with the internal nodes' own terms
        assert (d.sah_term / sah).sum() == pytest.approx(1.0, rel=1e-12)


def test_structure_against_the_node_array(small_tree):
    tris, bvh = small_tree
    d = bvh.node_data()
    nodes, children = bvh.nodes, _children(bvh)
    assert len(d) == len(nodes)
    np.testing.assert_array_equal(d.lo, nodes["lo"])
    np.testing.assert_array_equal(d.hi, nodes["hi"])
    np.testing.assert_array_equal(d.depth, bvh.depths)
    assert d.parent[0] == -1
    for i, kids in enumerate(children):
        assert (d.left[i], d.right[i]) == (kids if kids else (-1, -1))
        for c in kids:
            assert d.parent[c] == i
    slots = _subtree_slots(bvh)
    np.testing.assert_array_equal(d.prim_count, [len(s) for s in slots])
    assert d.prim_count[0] == len(tris)
    ext = nodes["hi"].astype(np.float64) - nodes["lo"]
    area = 2 * (ext[:, 0] * ext[:, 1] + ext[:, 1] * ext[:, 2] + ext[:, 2] * ext[:, 0])
    np.testing.assert_allclose(d.area, area, rtol=1e-12)


def test_child_overlap(small_tree):
    bvh = small_tree[1]
    d = bvh.node_data()
    for i in np.nonzero(d.left >= 0)[0]:
        a, b = d.left[i], d.right[i]
        e = np.minimum(d.hi[a], d.hi[b]).astype(np.float64) - np.maximum(d.lo[a], d.lo[b])
        inter = 0.0 if (e < 0).any() else 2 * (e[0] * e[1] + e[1] * e[2] + e[2] * e[0])
        assert d.child_overlap[i] == pytest.approx(inter / d.area[i], rel=1e-9, abs=1e-15)
    assert (d.child_overlap[d.left < 0] == 0).all()
    assert d.child_overlap.max() > 0, "the scene must have overlapping children to test"


def test_epo_against_a_brute_force_clip(small_tree):
    tris, bvh = small_tree
    d = bvh.node_data()
    refs = bvh.refs
    slots = _subtree_slots(bvh)
    t64 = tris.astype(np.float64)
    total = sum(0.5 * np.linalg.norm(np.cross(t[1] - t[0], t[2] - t[0])) for t in t64)
    leaf = bvh.is_leaf
    expected = np.zeros(len(d))
    for n in range(len(d)):
        inside = {int(refs[s]) for s in slots[n]}
        lo, hi = d.lo[n].astype(np.float64), d.hi[n].astype(np.float64)
        overlap = sum(_area_in_box(t64[t], lo, hi) for t in range(len(tris)) if t not in inside)
        cost = d.prim_count[n] if leaf[n] else 1
        expected[n] = cost * overlap / total
    np.testing.assert_allclose(d.epo, expected, rtol=1e-7, atol=1e-12)
    assert d.epo_cost == pytest.approx(expected.sum(), rel=1e-7)
    assert (expected > 0).sum() > len(d) // 4, "the scene must overlap enough to test EPO"


def test_epo_is_zero_for_boxes_apart():
    # two triangles far apart: no box holds anything of a triangle outside its subtree
    tris = np.array([[[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[5, 5, 5], [6, 5, 5], [5, 6, 5]]], np.float32)
    d = bvhlab.build(tris, method="median", max_leaf_size=1).node_data()
    assert d.epo_cost == 0 and len(d) == 3


def test_node_data_follows_refit(small_tree):
    tris, _ = small_tree
    bvh = bvhlab.build(tris, method="sah")
    before = bvh.node_data()
    bvh.refit(tris * 2)
    after = bvh.node_data()
    np.testing.assert_allclose(after.area, before.area * 4, rtol=1e-5)
    assert after.epo_cost == pytest.approx(before.epo_cost, rel=1e-6)  # a scale changes no ratio
    assert not after.lo.flags.writeable


def test_empty_tree_and_spheres():
    empty = bvhlab.build(np.zeros((0, 3, 3), np.float32))
    rest = empty.node_data(epo=False)
    assert len(rest) == 0 and empty.node_data(epo=False) is rest  # kept, though of length 0 (falsy)
    d = empty.node_data()
    assert len(d) == 0 and d.sah_cost == 0 and d.epo_cost == 0
    spheres = procedural.random_spheres(50, seed=1)
    d = bvhlab.build(np.zeros((0, 3, 3), np.float32), spheres).node_data()
    assert d.prim_count[0] == 50 and d.epo_cost == 0  # EPO counts triangles only


def test_node_data_does_not_depend_on_threads(knot_mesh):
    one = bvhlab.build(knot_mesh).node_data(threads=1)
    many = bvhlab.build(knot_mesh).node_data(threads=3)
    np.testing.assert_array_equal(one.epo, many.epo)  # fixed-point sums: bit for bit
    assert one.epo_cost == many.epo_cost > 0


def test_node_data_without_epo_is_the_rest_of_it_and_the_whole_serves_both(knot_mesh):
    """node_data(epo=False): every array but EPO equal to the whole data's bit for bit, EPO NaN (not
    a zero that reads as a figure); made after the whole data, it is the whole data; a snapshot and
    its tree share it. What Pick Box reads, at once (the EPO pass: 1.4 s of 1.45 at 1M triangles)."""
    bvh = bvhlab.build(knot_mesh)
    rest = bvh.node_data(epo=False)
    assert not rest.has_epo and np.isnan(rest.epo).all() and np.isnan(rest.epo_cost)
    assert bvh.cached_node_data() is None  # not analysed: no EPO made
    assert bvh._snapshot().node_data(epo=False) is rest
    whole = bvh.node_data()
    assert whole.has_epo and whole.epo_cost > 0
    for field in dataclasses.fields(whole):
        if field.name not in ("epo", "epo_cost"):
            np.testing.assert_array_equal(getattr(rest, field.name), getattr(whole, field.name), err_msg=field.name)
    assert bvh.node_data(epo=False) is whole
    with pytest.raises(TypeError):
        bvh.node_data(epo="no")
