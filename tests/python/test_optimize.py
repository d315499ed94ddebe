"""Bvh.optimize (issue 36; Bittner, Hapala and Havran 2013): the optimised tree is valid (its boxes
hold their primitives and children, skip indices are right, every primitive once), gives the hits
of brute force and of the tree before, never costs more, is the same for every thread count,
saves, loads and refits; hostile configs and stops are refused cleanly."""

import numpy as np
import pytest
from oracles import brute_force, check_tree_layout

import bvhlab
from bvhlab.cli import main
from bvhlab.library import procedural


@pytest.fixture(scope="module")
def knot():
    return procedural.torus_knot(30000)


def test_valid_cheaper_tree_with_the_same_hits(knot):
    tree = bvhlab.build(knot, method="median", max_leaf_size=3)
    before = tree.intersect(*procedural.random_rays(knot, 3000, seed=5))
    stats = tree.optimize(iterations=30, batch_fraction=0.05)
    assert isinstance(stats, bvhlab.OptimizeStats) and tree.revision == 1
    assert stats.sah_after < 0.9 * stats.sah_before  # a median tree leaves much to gain
    assert stats.sah_after == pytest.approx(tree.stats["sah_cost"], rel=1e-12)
    assert stats.reinsertions > 0 and stats.ms > 0 and stats.stop in ("converged", "iterations")
    assert tree.stats["max_leaf_size"] <= 3
    check_tree_layout(tree, knot)
    origins, dirs = procedural.random_rays(knot, 3000, seed=5)
    for traversal in bvhlab.TRAVERSALS:
        after = tree.intersect(origins, dirs, traversal=traversal)
        np.testing.assert_array_equal(after["t"], before["t"])
        np.testing.assert_array_equal(after["prim"], before["prim"])


def test_hits_equal_brute_force_with_spheres(small_scene):
    tris, spheres = small_scene
    tree = bvhlab.build(tris, spheres, method="midpoint", max_leaf_size=2)
    stats = tree.optimize()
    assert stats.sah_after <= stats.sah_before
    origins, dirs = procedural.random_rays(tris, 500, seed=9)
    t, prim, kind = brute_force(tris, spheres, origins, dirs)
    hits = tree.intersect(origins, dirs)
    np.testing.assert_allclose(hits["t"], t, rtol=1e-4)
    hit = np.isfinite(t)
    np.testing.assert_array_equal(hits["prim"][hit], prim[hit])
    np.testing.assert_array_equal(hits["kind"][hit], kind[hit])


def test_sah_never_increases_on_a_good_tree(knot):
    tree = bvhlab.build(knot)  # the default SAH tree
    stats = tree.optimize(iterations=10)
    assert stats.sah_after <= stats.sah_before
    assert tree.stats["sah_cost"] == pytest.approx(stats.sah_after, rel=1e-12)


def test_same_tree_for_every_thread_count(knot):
    trees = []
    for threads in (1, 2, 0):
        tree = bvhlab.build(knot, threads=threads)
        tree.optimize(iterations=15)
        trees.append(tree)
    for other in trees[1:]:
        np.testing.assert_array_equal(other.nodes, trees[0].nodes)
        np.testing.assert_array_equal(other.refs, trees[0].refs)


def test_saves_loads_and_refits(tmp_path, knot):
    tree = bvhlab.build(knot, method="lbvh")
    tree.optimize(iterations=10)
    path = tmp_path / "optimised.bvhtree"
    tree.save(path)
    loaded = bvhlab.load_bvh(path, knot)
    np.testing.assert_array_equal(loaded.nodes, tree.nodes)
    np.testing.assert_array_equal(loaded.refs, tree.refs)
    moved = np.ascontiguousarray(knot + np.float32(0.01) * np.sin(knot))
    tree.refit(moved)
    check_tree_layout(tree, moved)


@pytest.mark.parametrize(
    "changes",
    [{"time_budget_ms": -1.0}, {"time_budget_ms": float("nan")}, {"batch_fraction": 0.0},
     {"batch_fraction": 2.0}, {"iterations": -1}],
)  # fmt: skip
def test_hostile_configs_are_value_errors(small_scene, changes):
    tree = bvhlab.build(*small_scene)
    with pytest.raises(ValueError):
        tree.optimize(**changes)
    assert tree.revision == 0


def test_wrong_types_and_stops(small_scene, knot):
    tree = bvhlab.build(*small_scene)
    with pytest.raises(TypeError):
        tree.optimize(config={"iterations": 3})
    with pytest.raises(TypeError):
        tree.optimize(steps=3)
    with pytest.raises(TypeError, match="merge_leaves must be True or False, got 1"):
        bvhlab.OptimizeConfig(merge_leaves=1)
    assert bvhlab.OptimizeConfig(merge_leaves=np.False_).core().merge_leaves is False  # numpy's bool taken
    big = bvhlab.build(knot, method="median")
    nodes = big.nodes.copy()
    with pytest.raises(bvhlab.BuildCancelled):
        big.optimize(progress=lambda fraction: False)

    def fails(fraction):
        raise RuntimeError("from the callable")

    with pytest.raises(RuntimeError, match="from the callable"):
        big.optimize(progress=fails)
    assert big.revision == 0
    np.testing.assert_array_equal(big.nodes, nodes)
    stats = big.optimize(time_budget_ms=1e-6)
    assert stats.stop == "time_budget"
    check_tree_layout(big, knot)


def test_progress_follows_the_time_budget_and_ends_at_one(knot):
    """The fraction was of the iteration bound alone: 1,000 iterations in 300 ms stopped the bar at
    3%, and no run reported 1 (the bar ended at 90% and cleared: helper probe, 2026-12-07). The
    budget's run takes a mesh whose tree converges in ~1 s on the 2-core test machine (17× the
    budget): the 30,000-triangle knot converged in 55 ms there, and the test failed on a run
    where the budget of 60 ms was not reached."""
    big = procedural.torus_knot(300000)
    for mesh, changes in ((knot, dict(iterations=30)), (big, dict(iterations=100000, time_budget_ms=60.0))):
        seen = []
        stats = bvhlab.build(mesh, method="median").optimize(progress=seen.append, **changes)
        assert seen[-1] == 1.0 and seen == sorted(seen) and all(0 <= f <= 1 for f in seen)
        if "time_budget_ms" in changes:
            assert stats.stop == "time_budget" and stats.iterations < 1000
            assert max(seen[:-1]) > 0.5  # the time ran, not the iterations (< 1%)


def test_cli_build_and_inspect_optimize(tmp_path, capsys):
    assert main(["build", "gen:whitted", "--optimize", "5"]) == 0
    assert "optimized     SAH" in capsys.readouterr().out
    with pytest.raises(SystemExit) as refused:  # argparse's, before any work
        main(["build", "gen:whitted", "--optimize", "5", "--optimize-ms", "-3"])
    assert refused.value.code == 2
    assert "argument --optimize-ms: must be a finite number of ms" in capsys.readouterr().err  # its own name
    saved = tmp_path / "t.bvhtree"
    args = ["inspect", "gen:whitted", "--method", "median", "--worst", "2", "--save-tree", str(saved)]
    assert main(args) == 0
    median_sah = float(capsys.readouterr().out.split("sah_cost ")[1].split(",")[0])
    assert main([*args, "--optimize", "5"]) == 0
    assert float(capsys.readouterr().out.split("sah_cost ")[1].split(",")[0]) < median_sah
    knot = procedural.torus_knot(500)
    transforms = np.tile(np.eye(3, 4, dtype=np.float32), (2, 1, 1))
    transforms[1, 0, 3] = 3.0
    path = bvhlab.Scene(triangles=knot, instance_mesh=[0, 0], instance_transforms=transforms).save(tmp_path / "i.npz")
    assert main(["build", str(path), "--optimize", "5"]) == 2
    assert "flat scene" in capsys.readouterr().err


def test_a_change_of_the_tree_from_its_own_progress_callback_is_refused():
    # refit, update or optimize called from optimize's progress callable waited, on the same thread,
    # for the lock that optimize held: forever, and Ctrl-C could not end it (probe). In a child, so
    # that a regression fails by its timeout rather than hanging the run.
    from child import check_python

    out = check_python(
        """
        import numpy as np, bvhlab
        tris = np.random.default_rng(0).random((3000, 3, 3), dtype=np.float32)
        for change in ("refit", "update", "optimize"):
            bvh = bvhlab.build(tris)
            calls = []
            def progress(fraction):
                try:
                    getattr(bvh, change)(tris) if change != "optimize" else bvh.optimize(iterations=1)
                    calls.append("changed")
                except RuntimeError as error:
                    calls.append(str(error))
                return True
            bvh.optimize(iterations=2, progress=progress)
            assert calls and all("this tree is busy on this thread" in c for c in calls), calls
            bvh.refit(tris)  # after its work, a change goes through
        print("refused")
        """,
        timeout=120,
    )
    assert out.strip() == "refused"
