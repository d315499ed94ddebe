"""A render that keeps no cost (Renderer.start(keep_cost=False): what Renderer.render, the render
CLI and the add-on's renders ask for where no heatmap pass is shown): the CPU tracer's wide walk
traces a flat scene's camera rays ahead, eight at a time through the batch's packets (the AVX2
path), and the image is the same bit for bit."""

import os
from pathlib import Path

import numpy as np
import pytest

import bvhlab
from bvhlab.library import showcase

#: Whether the library runs its AVX2 path here (isa.h: the best the CPU has, unless BVHLAB_ISA
#: lowers it), the one with packets: elsewhere the camera rays go alone, none traced ahead.
PACKETS = "avx2" in Path("/proc/cpuinfo").read_text().split() and os.environ.get("BVHLAB_ISA") != "portable"


def test_a_job_without_the_cost_traces_camera_rays_ahead_and_refuses_the_cost():
    """Renderer.start(keep_cost=False) (what Renderer.render, the render CLI and the add-on's
    renders ask for where no heatmap pass is shown): the wide walk traces a flat scene's camera
    rays ahead, eight at a time where they run together; the same image bit for bit, every camera
    ray answered so; the cost and the heat refused, and the heatmap mode, whose image the cost is,
    keeps it."""
    scene = showcase.whitted()
    bvh = bvhlab.build(scene)
    renderer = bvhlab.Renderer("cpu")
    jobs = {}
    for keep in (True, False):
        job = renderer.start(scene, bvh, 64, 48, samples_per_axis=2, traversal="wide", keep_cost=keep)
        job.run()
        jobs[keep] = job
    kept, ahead = jobs[True].result(), jobs[False].result()
    assert kept.cost is not None and ahead.cost is None  # cost None: where the job keeps it
    np.testing.assert_array_equal(ahead.color, kept.color)
    np.testing.assert_array_equal(ahead.depth, kept.depth)
    assert kept.timings["camera_rays_ahead"] == 0
    assert ahead.timings["camera_rays_ahead"] == (64 * 48 * 4 if PACKETS else 0)
    for images in ({"cost": True}, {"heat": True}):
        with pytest.raises(ValueError, match="keep_cost"):
            jobs[False].result(**images)
    image, timings = renderer.render(scene, bvh, 64, 48, samples_per_axis=2, traversal="wide")
    np.testing.assert_array_equal(image, kept.color)
    assert timings["camera_rays_ahead"] == (64 * 48 * 4 if PACKETS else 0)
    heat = renderer.start(scene, bvh, 64, 48, mode="heatmap", traversal="wide", keep_cost=False)
    heat.run()
    assert heat.result(heat=True).cost is not None
    with pytest.raises(TypeError):
        renderer.start(scene, bvh, 64, 48, keep_cost="no")
