"""A RenderJob's run arguments (probe): a progress that is not callable is refused before any
sample (it was called as one at the first check: "'int' object is not callable"), and a stopped
run names the samples it was asked for, not the job's own count."""

import numpy as np
import pytest

import bvhlab
from bvhlab.library import procedural


@pytest.fixture(scope="module")
def job_parts():
    tris = procedural.random_triangles(200, size=0.2, seed=3)
    scene = bvhlab.Scene(triangles=tris)
    return scene, bvhlab.build(scene)


def test_a_progress_that_is_not_callable_is_refused(job_parts):
    job = bvhlab.Renderer("cpu").start(*job_parts, 8, 6)
    with pytest.raises(TypeError, match="progress must be callable"):
        job.run(1, progress=5)
    assert job.samples_done == 0
    job.run(1)
    assert job.samples_done == 1 and np.isfinite(job.result().color).all()


def test_a_stopped_run_names_the_samples_asked_for(job_parts):
    job = bvhlab.Renderer("cpu").start(*job_parts, 8, 6)  # one sample per pixel of its own
    with pytest.raises(bvhlab.RenderCancelled, match="of 9 samples per pixel"):
        job.run(9, progress=lambda fraction: False)
