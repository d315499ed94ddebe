"""Renders that must neither crash, hang nor ignore the user (issue 8, items 4, 11, 12): several
threads rendering at once (Vulkan and the CPU reference), the overlay at a tiny field of view,
Ctrl-C during a long render. Hang and crash cases run in a subprocess with a timeout."""

import signal
import subprocess
import sys
import threading
import time

import numpy as np
import pytest
from child import default_sigint

import bvhlab
from bvhlab.library import showcase


def test_threads_rendering_at_once_get_their_serial_images():
    """Six threads, Vulkan (one shared renderer, and the process-wide default) and CPU (the wide
    traversal on a shared renderer too, its tree's wide copy made by whichever thread comes first),
    each rendering a few frames of its own settings: every image equals the same render made alone."""
    scene = showcase.whitted()
    bvh = bvhlab.build(scene)
    shared = bvhlab.Renderer("vulkan", validation=True)
    cpu = bvhlab.Renderer("cpu", threads=2)
    jobs = [
        (shared, dict(samples_per_axis=2)),
        (shared, dict(traversal="stackless", overlay_depth=(1, 3))),
        (bvhlab.render, dict(backend="vulkan", mode="heatmap")),
        (bvhlab.render, dict(backend="cpu", samples_per_axis=2, threads=1)),
        (cpu, dict(traversal="wide", samples_per_axis=2)),
        (cpu, dict(traversal="wide", mode="heatmap")),
    ]

    def run(target, options, tree=bvh):
        return (
            target.render(scene, tree, 40, 30, **options)[0]
            if isinstance(target, bvhlab.Renderer)
            else target(scene, tree, 40, 30, **options)[0]
        )

    serial = [run(target, options) for target, options in jobs]
    fresh = bvhlab.build(scene)  # the same tree, no wide copy yet: the threads race to make it
    results, errors = [None] * len(jobs), []

    def worker(k):
        try:
            for _ in range(3):
                results[k] = run(*jobs[k], tree=fresh)
        except Exception as e:  # noqa: BLE001 (reported below)
            errors.append(e)

    threads = [threading.Thread(target=worker, args=(k,)) for k in range(len(jobs))]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert not errors, errors
    for k, image in enumerate(results):
        np.testing.assert_array_equal(image, serial[k], err_msg=f"job {k}")
    assert shared.validation_errors == 0, shared.validation_messages()


def run_python(code: str, timeout: float) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=timeout)


@pytest.mark.parametrize("fov", [1e-6, 1e-7])
def test_overlay_at_a_tiny_field_of_view_finishes(fov):
    """4×4 pixels, the boxes of every depth, a field of view of 1e-6 degrees: lines run to ±1e9
    pixels before clipping (they once stepped there, 14 s and >100 s); now clipped to the view."""
    code = (
        "import bvhlab\nfrom bvhlab.library import showcase\n"
        "s = showcase.whitted(); b = bvhlab.build(s)\n"
        f"cam = bvhlab.Camera((0.3, -6, 2), (0.2, 0, 0.5), fov_y={fov})\n"
        "img, _ = bvhlab.render(s, b, 4, 4, backend='cpu', camera=cam, overlay_depth=(0, 20))\n"
        "print('OK', img.shape)\n"
    )
    out = run_python(code, timeout=120)
    assert out.returncode == 0 and "OK (4, 4, 4)" in out.stdout, out.stderr


def test_overlay_of_boxes_at_huge_coordinates_and_through_the_camera():
    """A crafted scene: boxes as wide as the supported coordinate range (±2^40) around and behind
    the camera (lines cross the eye plane and project far outside the image before clipping)."""
    r = float(bvhlab.scene.MAX_COORDINATE)
    tris = np.array([[[-r, -r, -r], [r, -r, r], [0, r, 0]], [[-1, -1, -1], [1, -1, 1], [0, 1, 0]]], np.float32)
    scene = bvhlab.Scene(triangles=tris, camera=bvhlab.Camera((0, -3, 0), (0, 0, 0)))
    code = (
        "import numpy as np, bvhlab\n"
        f"tris = np.array({tris.tolist()!r}, np.float32)\n"
        "s = bvhlab.Scene(triangles=tris, camera=bvhlab.Camera((0, -3, 0), (0, 0, 0)))\n"
        "img, _ = bvhlab.render(s, bvhlab.build(s, method='median'), 32, 24, backend='cpu', overlay_depth=(0, 5))\n"
        "print('OK', bool(np.isfinite(img).all()))\n"
    )
    out = run_python(code, timeout=120)
    assert out.returncode == 0 and "OK True" in out.stdout, out.stderr
    assert scene.primitive_count == 2


LONG_RENDER = """
import sys, time, bvhlab
from bvhlab.library import procedural
s = bvhlab.Scene(triangles=procedural.torus_knot(60000)); b = bvhlab.build(s)
print("READY", flush=True)
start = time.monotonic()
try:
    bvhlab.render(s, b, 1600, 1200, backend=sys.argv[1], samples_per_axis=16, max_depth=15)
    print("FINISHED", time.monotonic() - start)
except KeyboardInterrupt:
    print("INTERRUPTED", time.monotonic() - start, flush=True)
"""


@pytest.mark.parametrize("backend", ["cpu", "vulkan"])
def test_ctrl_c_stops_a_long_render(backend):
    """A render of several minutes is interrupted 2 s in: KeyboardInterrupt arrives (CPU: between
    budgets of steps, Vulkan: between dispatches) instead of the render running on."""
    p = subprocess.Popen(
        [sys.executable, "-c", LONG_RENDER, backend],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        preexec_fn=default_sigint,
    )
    assert p.stdout.readline().strip() == "READY"
    time.sleep(2.0)
    p.send_signal(signal.SIGINT)
    try:
        out, err = p.communicate(timeout=60)
    except subprocess.TimeoutExpired:
        p.kill()
        pytest.fail("the render ignored Ctrl-C for a minute")
    assert "INTERRUPTED" in out, (out, err)
