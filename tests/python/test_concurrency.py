"""Several Python threads at once on the core (issue 8, "keep it so"): builds (with progress
callables, some cancelling), intersect, refit, update and boxes on shared trees, for a few seconds; no
crash, and every result equal to the serial one. It runs in a child process, so a crash fails the
test instead of the test run. Each workload is a function in WORKLOADS: add one to cover more."""

from child import check_python

CHILD = """
    import sys, threading, time
    import numpy as np
    import bvhlab
    from bvhlab.library import procedural

    DURATION = float(sys.argv[1]) if len(sys.argv) > 1 else 3.0
    tris = procedural.torus_knot(30000)
    moved = tris + np.float32(0.25)
    moved[::4] *= np.float32(1.2)
    spheres = procedural.random_spheres(200, seed=3)
    o, d = procedural.random_rays(tris, 20000, seed=5)
    METHODS = ("sah", "median", "lbvh", "sweep_sah")

    # Serial answers first: every tree and every query the threads will make.
    serial_trees = {(m, g): bvhlab.build(geo, spheres, method=m, threads=1)
                    for m in METHODS for g, geo in (("a", tris), ("b", moved))}
    tree_bytes = {k: (t.nodes.tobytes(), t.refs.tobytes()) for k, t in serial_trees.items()}
    hits = {g: serial_trees[("sah", g)].intersect(o, d) for g in ("a", "b")}
    refitted = bvhlab.build(tris, spheres, method="sah")  # the shared tree's two versions, made serially
    boxes = {"a": refitted.boxes(0, 7)}
    refitted.refit(moved, spheres)
    boxes["b"] = refitted.boxes(0, 7)
    shared = bvhlab.build(tris, spheres, method="sah")
    updated = bvhlab.build(tris, spheres, method="sah")  # updated by every policy meanwhile
    failures, counts = [], {}
    stop_at = time.monotonic() + DURATION

    def fail(text):
        failures.append(text)

    def same_hits(h, g):
        return all(np.array_equal(h[k], hits[g][k]) for k in ("t", "prim", "kind", "u", "v"))

    def builds(k):
        rng = np.random.default_rng(k)
        while time.monotonic() < stop_at:
            m, g = METHODS[rng.integers(len(METHODS))], "ab"[rng.integers(2)]
            geo = tris if g == "a" else moved
            if rng.random() < 0.2:  # a cancelled build beside the others
                try:
                    bvhlab.build(geo, spheres, method=m, progress=lambda f: np.bool_(f < 0.3))
                    fail("a build whose progress said stop was not cancelled")
                except bvhlab.BuildCancelled:
                    pass
                continue
            threads = int((0, 1, 2, 8)[rng.integers(4)])  # 8: the top's small nodes and parts from one queue
            t = bvhlab.build(geo, spheres, method=m, threads=threads, progress=lambda f: f >= np.float64(0))
            if (t.nodes.tobytes(), t.refs.tobytes()) != tree_bytes[(m, g)]:
                fail(f"{m} tree of {g} differs from the serial one")
            counts["build"] = counts.get("build", 0) + 1

    def private_intersect(k):  # a tree of its own: exactly the serial hits
        t = bvhlab.build(tris, spheres, method="sah")
        while time.monotonic() < stop_at:
            if not same_hits(t.intersect(o, d, traversal=("wide", "stack", "stackless")[k % 3]), "a"):
                fail("intersect on a private tree differs from the serial hits")
            counts["intersect"] = counts.get("intersect", 0) + 1
            k += 1

    def shared_intersect(k):  # the shared tree is refitted meanwhile: hits of one version or the other
        while time.monotonic() < stop_at:
            h = shared.intersect(o, d, traversal=("wide", "stack", "stackless")[k % 3])
            if not (same_hits(h, "a") or same_hits(h, "b")):
                fail("intersect on the shared tree gave hits of neither version")
            k += 1

    def refits(k):
        while time.monotonic() < stop_at:
            shared.refit(moved if k % 2 == 0 else tris, spheres)
            k += 1
        counts["refit"] = k

    def updates(k):  # issue 34: each policy publishes a whole new version; readers keep theirs
        while time.monotonic() < stop_at:
            updated.update(moved if k % 2 == 0 else tris, spheres, policy=bvhlab.UPDATE_POLICIES[k % 4])
            k += 1
        counts["update"] = k

    def updated_intersect(k):  # any valid tree over the same geometry gives the same hits
        while time.monotonic() < stop_at:
            h = updated.intersect(o, d, traversal=("wide", "stack", "stackless")[k % 3])
            if not (same_hits(h, "a") or same_hits(h, "b")):
                fail("intersect on the updated tree gave hits of neither geometry")
            k += 1

    def shared_boxes(k):
        while time.monotonic() < stop_at:
            got = shared.boxes(0, 7)
            if not any(all(np.array_equal(x, y) for x, y in zip(got, boxes[g])) for g in ("a", "b")):
                fail("boxes of the shared tree are of neither version")

    WORKLOADS = [builds, builds, private_intersect, shared_intersect, shared_intersect, refits, shared_boxes,
                 updates, updated_intersect]
    threads = [threading.Thread(target=w, args=(k,)) for k, w in enumerate(WORKLOADS)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    print("counts", counts, "failures", len(failures), sorted(set(failures))[:5])
    enough = counts.get("build", 0) >= 2 and counts.get("refit", 0) >= 4 and counts.get("intersect", 0) >= 2
    enough = enough and counts.get("update", 0) >= 4
    ok = not failures and enough
    sys.exit(0 if ok else 1)
"""


def test_threads_share_the_core_and_get_serial_results():
    out = check_python(CHILD, timeout=300)
    assert "failures 0" in out, out
