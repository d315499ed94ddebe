"""A mesh tree of an InstancedBvh changed through `meshes[k]` (refit, update): a change that moves an
instance outside the coordinate range is refused and undone, and the InstancedBvh keeps answering
(it kept the change, and every later read raised, `meshes` too: a helper's audit)."""

import gc

import numpy as np
import pytest

import bvhlab

TRIANGLE = np.array([[[0, 0, 0], [1, 0, 0], [0, 1, 0]]], np.float32)
MESH = np.concatenate([TRIANGLE, TRIANGLE + 2])


def _scene(scale: float = 1e6) -> bvhlab.Scene:
    """Mesh 0 as modelled; mesh 1 placed once where modelled and once scaled by `scale` at x = 5."""
    transforms = np.zeros((3, 3, 4), np.float32)
    transforms[:, :, :3] = np.eye(3)
    transforms[2, :, :3] *= scale
    transforms[2, 0, 3] = 5
    return bvhlab.Scene(
        triangles=MESH, meshes=[MESH], instance_mesh=np.array([0, 1, 1]), instance_transforms=transforms
    )


def _rays(n: int = 500):
    rng = np.random.default_rng(3)
    origins = rng.uniform(-3, 6, (n, 3)).astype(np.float32)
    origins[:, 2] = 5
    dirs = np.tile(np.float32([0, 0, -1]), (n, 1))
    return origins, dirs


@pytest.mark.parametrize("how", ["refit", "update", "update_rebuild"])
def test_a_change_that_moves_an_instance_out_of_range_is_refused_and_undone(how):
    tree = bvhlab.build(_scene())
    origins, dirs = _rays()
    before = tree.intersect(origins, dirs)
    stats = tree.stats
    mesh = tree.meshes[1]
    revision = mesh.revision
    far = MESH + np.float32(1e7)  # within range in the mesh's space, ×1e6 past 2^40 in the world
    change = {
        "refit": lambda: mesh.refit(far),
        "update": lambda: mesh.update(far, policy="refit"),
        "update_rebuild": lambda: mesh.update(far, policy="rebuild"),
    }[how]
    with pytest.raises(ValueError, match=r"change refused, the tree kept as it was.*instance 2.*coordinate range"):
        change()
    # the tree as it was, and its revision: the change was made on a fork, never published (it
    # was published, then undone as a new revision)
    assert mesh.revision == revision
    np.testing.assert_array_equal(mesh.refs, tree.meshes[1].refs)
    assert float(mesh.nodes["hi"].max()) == pytest.approx(3.0)
    after = tree.intersect(origins, dirs)
    for key in ("t", "prim", "instance"):
        np.testing.assert_array_equal(after[key], before[key])
    timeless = lambda s: {k: v for k, v in s.items() if not k.endswith("_ms")}  # noqa: E731
    assert timeless(tree.stats) == timeless(stats)
    # and a change within range is taken and followed
    near = MESH + np.float32([0, 0, 1])
    mesh.refit(near)
    moved = bvhlab.build(
        bvhlab.Scene(
            triangles=MESH, meshes=[near], instance_mesh=tree.instances[0], instance_transforms=tree.instances[1]
        )
    )
    np.testing.assert_array_equal(tree.intersect(origins, dirs)["t"], moved.intersect(origins, dirs)["t"])


def test_every_instanced_tree_placing_the_mesh_is_asked():
    """Two InstancedBvhs over the same mesh trees: one places it by 1 (the change fits), the other
    by 1e6 (it does not): refused for both, and neither raises afterwards."""
    small = bvhlab.build(_scene(scale=1.0))
    meshes = list(small.meshes)
    mesh_of, transforms = _scene().instances()
    large = bvhlab.InstancedBvh(meshes, mesh_of, transforms, small.config)
    with pytest.raises(ValueError, match="instance 2"):
        meshes[1].refit(MESH + np.float32(1e7))
    origins, dirs = _rays(50)
    for placed in (small, large):
        assert placed.stats["instances"] == 3
        assert np.isfinite(placed.intersect(origins, dirs)["t"]).any()
    del large, placed  # no longer places it: the same change is now the small tree's alone, and fits
    gc.collect()
    meshes[1].refit(MESH + np.float32(1e7))
    assert small.world_boxes()[1][2, 0] == pytest.approx(1e7 + 8, rel=1e-5)


def test_a_snapshot_does_not_refuse_changes():
    """A snapshot keeps the TLAS it was taken with and places nothing new: a change its placement
    would refuse is taken where the live tree's placement allows it."""
    tree = bvhlab.build(_scene())  # instance 2 scaled by 1e6
    view = tree.snapshot()
    tree.place(*_scene(scale=1.0).instances())
    tree.meshes[1].refit(MESH + np.float32(1e7))  # ×1e6 past 2^40 in the snapshot's placement
    assert view.world_boxes()[1][2, 0] == pytest.approx(3e6 + 5, rel=1e-5)
    assert tree.world_boxes()[1][2, 0] == pytest.approx(1e7 + 8, rel=1e-5)


def test_a_tlas_is_refused_as_a_mesh():
    """`InstancedBvh([tree.tlas], ...)`: its references are instances, not primitives; its walk as a
    mesh read primitives that are not there (a segfault: a helper's audit)."""
    tree = bvhlab.build(_scene(scale=1.0))
    mesh_of, transforms = tree.instances
    with pytest.raises(ValueError, match="mesh 1: this tree holds no geometry"):
        bvhlab.InstancedBvh([tree.meshes[0], tree.tlas], mesh_of, transforms, tree.config)


def test_update_mesh_checks_its_config_whatever_the_counts():
    tree = bvhlab.build(_scene(scale=1.0))
    more = np.concatenate([MESH, TRIANGLE + 5])  # another count: a rebuild, which took any config
    with pytest.raises(ValueError, match="policy"):
        tree.update_mesh(1, more, policy="bogus")
    with pytest.raises(TypeError, match="nosuch"):
        tree.update_mesh(1, more, nosuch=1)
    with pytest.raises(TypeError, match="config must be a bvhlab.UpdateConfig"):
        tree.update_mesh(1, more, config="adaptive")
    assert tree.meshes[1].stats["primitives"] == 2
    assert tree.update_mesh(1, more, policy="adaptive").policy == "rebuild"
    assert tree.meshes[1].stats["primitives"] == 3


def test_spheres_given_to_a_mesh_other_than_0_through_meshes_k_are_refused():
    """update_mesh refuses spheres beyond mesh 0 (no Scene describes such a tree); `meshes[k].update`
    with policy "rebuild" took them, and the tree answered sphere hits in mesh 1."""
    tree = bvhlab.build(_scene(scale=1.0))
    spheres = np.array([[0, 0, 0, 0.5]], np.float32)
    with pytest.raises(ValueError, match="mesh 1 cannot hold spheres"):
        tree.meshes[1].update(MESH, spheres, policy="rebuild")
    assert tree.meshes[1]._core.primitive_counts == (2, 0)
    hits = tree.intersect(np.float32([[0.2, 0.2, 5]]), np.float32([[0, 0, -1]]))
    assert hits["kind"][0] == 0  # a triangle


def test_update_mesh_names_the_new_geometry_for_an_instance_it_moves_out_of_range():
    tree = bvhlab.build(_scene())
    with pytest.raises(ValueError, match=r"mesh 1's new geometry refused.*instance 2 would place mesh 1 outside"):
        tree.update_mesh(1, MESH + np.float32(1e7))


def test_a_transform_with_nearly_parallel_axes_names_the_measure_it_failed():
    """A shear of determinant 1 with nearly parallel axes: "determinant 1" alone read as a
    contradiction; the message gives the ratio the test compares."""
    transforms = np.zeros((1, 3, 4), np.float32)
    transforms[0, :, :3] = [[1, 1e6, 0], [0, 1, 0], [0, 0, 1]]
    scene = bvhlab.Scene(meshes=[MESH], instance_mesh=np.array([1]), instance_transforms=transforms)
    with pytest.raises(ValueError, match=r"\|determinant\| 1 is 1e-06 of the product of its axes' lengths"):
        bvhlab.build(scene)


def test_height_counts_only_placed_meshes():
    deep = np.random.default_rng(5).uniform(-1, 1, (3000, 3, 3)).astype(np.float32)
    transforms = np.zeros((1, 3, 4), np.float32)
    transforms[0, :, :3] = np.eye(3)
    scene = bvhlab.Scene(meshes=[deep, MESH], instance_mesh=np.array([2]), instance_transforms=transforms)
    stats = bvhlab.build(scene).stats
    assert stats["mesh_height"][1] > 5
    assert stats["height"] == stats["tlas_height"] + stats["mesh_height"][2]


def test_an_optimisation_that_moves_an_instance_out_of_range_is_refused_and_undone():
    """Optimising reshapes the tree, and with it the top boxes a TLAS moves into the world: a
    rotated instance placed just inside -2^40 left it, and every later read raised (the review)."""
    from bvhlab.library import procedural

    tris = procedural.random_triangles(2000, size=0.05, seed=29)
    c, s = np.cos(0.7), np.sin(0.7)

    def placed(tx: float):
        transform = np.float32([[c * 1e9, -s * 1e9, 0, tx], [s * 1e9, c * 1e9, 0, 0], [0, 0, 1e9, 0]])
        return bvhlab.build(
            bvhlab.Scene(
                triangles=tris[:1], meshes=[tris], instance_mesh=np.array([1]), instance_transforms=transform[None]
            )
        )

    probe = placed(0.0)
    lo0 = probe.world_boxes()[0][0, 0]
    probe.meshes[1].optimize(iterations=50)
    grown = float(lo0 - probe.world_boxes()[0][0, 0])
    assert grown > 0  # the optimised tree's top boxes reach further out
    tree = placed(-(2.0**40) - float(lo0) + grown / 2)  # inside before, outside after
    revision = tree.meshes[1].revision
    with pytest.raises(ValueError, match="change refused.*instance 0 would place mesh 1 outside"):
        tree.meshes[1].optimize(iterations=50)
    assert tree.meshes[1].revision == revision
    assert tree.world_boxes()[0][0, 0] >= -(2.0**40)


def test_a_change_while_an_instanced_tree_is_made_over_the_mesh_is_checked(monkeypatch):
    """A refit of a mesh between an InstancedBvh's TLAS and its learning of its meshes went
    unchecked, and the new tree's next read raised (the review). It waits for the tree now."""
    import threading

    import bvhlab.instanced as instanced

    base = bvhlab.build(_scene(scale=1.0))
    meshes = list(base.meshes)
    mesh_of, transforms = _scene().instances()  # instance 2 scaled by 1e6
    refused: list = []
    started: list = []
    made = instanced._make_tlas

    def refit_meanwhile(*args, **kwargs):
        def refit():
            try:
                meshes[1].refit(MESH + np.float32(1e7))
            except ValueError as e:
                refused.append(e)

        thread = threading.Thread(target=refit)
        thread.start()
        started.append(thread)
        thread.join(0.2)  # it waits for the tree being made (a deadlock would fail below)
        return made(*args, **kwargs)

    monkeypatch.setattr(instanced, "_make_tlas", refit_meanwhile)
    tree = bvhlab.InstancedBvh(meshes, mesh_of, transforms, base.config)
    monkeypatch.setattr(instanced, "_make_tlas", made)
    started[0].join(10)
    assert refused and "instance 2 would place mesh 1 outside" in str(refused[0])
    assert tree.stats["instances"] == 3


def test_a_refused_change_is_never_seen_by_the_trees_readers():
    """Published first and undone after the check, a refused refit was seen by another thread's
    reads of the mesh tree (about half of them: an audit); each refusal cost two revisions."""
    import threading
    import time

    tree = bvhlab.build(_scene())
    mesh = tree.meshes[1]
    far = MESH + np.float32(1e7)  # refused: instance 2 (scaled by 1e6) would leave the range
    origin, down = np.float32([[1e7 + 0.25, 1e7 + 0.25, 1e7 + 5]]), np.float32([[0, 0, -1]])
    assert np.isfinite(bvhlab.build(far).intersect(origin, down)["t"][0])  # the ray hits `far`
    revision, stop, seen, refused = mesh.revision, time.monotonic() + 1.5, [], []

    def refit():
        while time.monotonic() < stop:
            with pytest.raises(ValueError, match="change refused"):
                mesh.refit(far)
            refused.append(1)

    def read():
        while time.monotonic() < stop:
            seen.append(bool(np.isfinite(mesh.intersect(origin, down, threads=1)["t"][0])))

    threads = [threading.Thread(target=refit), threading.Thread(target=read)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert len(refused) > 20 and len(seen) > 20
    assert not any(seen), f"{sum(seen)} of {len(seen)} reads saw the refused geometry"
    assert mesh.revision == revision


@pytest.mark.parametrize(
    "meshes, config, message",
    [
        ("good and none", "config", r"meshes\[1\] must be a bvhlab.Bvh \(a flat tree\), got NoneType"),
        ("good and array", "config", r"meshes\[1\] must be a bvhlab.Bvh \(a flat tree\), got ndarray"),
        ("good and two-level", "config", r"meshes\[1\] must be .*got InstancedBvh \(two-level trees do not nest\)"),
        ("good", None, "config must be a bvhlab.BuildConfig, got NoneType"),
        ("good", {}, "config must be a bvhlab.BuildConfig, got dict"),
    ],
)
def test_an_instanced_tree_refused_for_its_arguments_leaves_the_meshes_alone(meshes, config, message):
    """A refused InstancedBvh(...) told the good trees before the bad one that it placed them, and
    while its exception was kept (a REPL's last error, a logged one) their changes failed with a
    TypeError of its own; a mesh that was not a tree, or config None, was an AttributeError (an
    audit)."""
    good = bvhlab.build(MESH)
    other = {"good": [], "good and none": [None], "good and array": [MESH], "good and two-level": None}[meshes]
    if other is None:
        other = [bvhlab.build(_scene())]
    transforms = np.tile(np.eye(3, 4, dtype=np.float32), (2, 1, 1))
    with pytest.raises(TypeError, match=message) as kept:
        bvhlab.InstancedBvh([good, *other], np.zeros(2, np.int32), transforms, good.config if config else config)
    assert kept.value is not None  # held while the tree is changed
    revision = good.revision
    good.refit(MESH + 1)
    good.update(MESH + 2)
    good.optimize()
    assert good.revision == revision + 3
