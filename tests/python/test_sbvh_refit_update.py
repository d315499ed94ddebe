"""An SBVH that a refit rebuilt (its leaf boxes hold clipped parts) can be updated afterwards
(probe): the refit's new topology carries its own costs as built, not the old tree's."""

import numpy as np
import pytest

import bvhlab
from bvhlab.library import procedural


@pytest.mark.parametrize("policy", ["adaptive", "partial", "refit", "rebuild"])
def test_update_after_an_sbvh_refit_gives_a_fresh_builds_hits(policy):
    rng = np.random.default_rng(4)
    tris = rng.random((300, 3, 3), dtype=np.float32)  # large, overlapping: many spatial splits
    moved = np.ascontiguousarray(tris + rng.normal(0, 0.05, tris.shape).astype(np.float32))
    again = np.ascontiguousarray(tris + rng.normal(0, 0.05, tris.shape).astype(np.float32))
    bvh = bvhlab.build(tris, method="sbvh")
    bvh.refit(moved)  # an SBVH is rebuilt here: another node count than the tree it replaced
    bvh.update(again, policy=policy)
    o, d = procedural.random_rays(again, 500, seed=5)
    got, want = bvh.intersect(o, d), bvhlab.build(again).intersect(o, d)
    np.testing.assert_array_equal(got["t"], want["t"])
    np.testing.assert_array_equal(got["prim"], want["prim"])
    assert bvh.revision == 2


@pytest.mark.parametrize("policy", ["refit", "partial", "adaptive"])
def test_an_sbvh_update_that_keeps_primitives_refuses_other_counts_as_refit_does(policy):
    # refit refused 60 triangles for a tree of 100; update rebuilt over them and said "rebuild" (probe)
    tris = np.random.default_rng(3).random((100, 3, 3), dtype=np.float32)
    bvh = bvhlab.build(tris, method="sbvh")
    before = bvh.revision
    with pytest.raises(ValueError, match="keeps the tree's primitives"):
        bvh.update(tris[:60], policy=policy)
    assert bvh.revision == before  # the tree as it was
    assert bvh.update(tris[:60], policy="rebuild").policy == "rebuild"
    assert bvh.stats["triangles"] == 60
