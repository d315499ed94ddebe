"""A Bvh shared between threads (issue 8.3): readers see the old tree or the new one, never freed
memory; a tree used with other geometry is refused (issue 8.8). The races run in a child process,
so a crash fails the test instead of the test run."""

import subprocess
import sys
import textwrap

import numpy as np
import pytest

import bvhlab
from bvhlab.library import procedural

RACE = textwrap.dedent("""
    import sys, threading, time
    import numpy as np
    import bvhlab
    from bvhlab.library import procedural

    tris = procedural.torus_knot(40000)
    moved = (tris + np.float32(0.25)).astype(np.float32)
    bvh = bvhlab.build(tris)
    o, d = procedural.random_rays(tris, 20000, seed=3)
    probe = bvhlab.build(tris)
    probe.refit(moved)
    versions = [bvh.intersect(o, d)["t"], probe.intersect(o, d)["t"]]  # hits of the two geometries
    lo0, hi0, depth0 = bvh.boxes(0, 6)
    failures, stop = [], time.monotonic() + 3.0

    def refitter():
        k = 0
        while time.monotonic() < stop:
            bvh.refit(moved if k % 2 == 0 else tris)
            k += 1

    def reader(kind):
        while time.monotonic() < stop:
            if kind == "rays":
                t = bvh.intersect(o, d, traversal=["wide", "stack", "stackless"][int(time.monotonic() * 7) % 3])["t"]
                if not any(np.array_equal(t, v) for v in versions):
                    failures.append("intersect returned hits of neither version")
            else:
                lo, hi, depth = bvh.boxes(0, 6)
                same_boxes = np.array_equal(lo, lo0) or np.allclose(lo, lo0 + 0.25, atol=1e-3)
                if not (np.array_equal(depth, depth0) and same_boxes):
                    failures.append("boxes returned boxes of neither version")

    readers = [threading.Thread(target=reader, args=(k,)) for k in ("rays", "rays", "boxes")]
    threads = [threading.Thread(target=refitter)] + readers
    for t in threads: t.start()
    for t in threads: t.join()
    print("revision", bvh.revision, "failures", len(failures), failures[:3])
    sys.exit(1 if failures or bvh.revision < 4 else 0)
""")


def test_refit_while_other_threads_read():
    done = subprocess.run([sys.executable, "-c", RACE], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, f"exit {done.returncode}\n{done.stdout[-3000:]}\n{done.stderr[-3000:]}"


def test_arrays_of_an_old_version_stay_valid_after_refit():
    tris = procedural.random_triangles(500, seed=1)
    bvh = bvhlab.build(tris)
    nodes, refs = bvh.nodes, bvh.refs
    before = nodes.copy()
    bvh.refit(tris * np.float32(2))
    assert bvh.revision == 1
    np.testing.assert_array_equal(nodes, before)  # the old version, kept alive by the array
    assert not np.array_equal(bvh.nodes["hi"], before["hi"])
    assert len(refs) == 500


def test_render_refuses_a_tree_of_other_geometry():
    tris = procedural.random_triangles(300, seed=2)
    other = procedural.random_triangles(300, seed=3)
    bvh = bvhlab.build(tris)
    with pytest.raises(ValueError, match="other geometry"):
        bvhlab.render(bvhlab.Scene(triangles=other), bvh, 16, 12, backend="cpu")
    scene = bvhlab.Scene(triangles=tris)
    bvhlab.render(scene, bvh, 16, 12, backend="cpu")
    scene.triangles = other  # reassigned after a render: detected, not served from a cache
    with pytest.raises(ValueError, match="other geometry"):
        bvhlab.render(scene, bvh, 16, 12, backend="cpu")
    bvh.refit(other)  # refitted to the new geometry: fine again
    image, _ = bvhlab.render(scene, bvh, 16, 12, backend="cpu")
    assert np.isfinite(image).all()
