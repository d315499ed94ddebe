"""A render's progress callable that reaches what another thread holds (helper probe, 2026-12-07):
on a shared Vulkan Renderer, a callable that started a job while a second thread was starting one,
or read a second job while another thread ran it, waited for good with that thread, which waited
for the locks the callable's run held. Now the callable's thread never waits for a lock of the
same rank or below (owned_mutex.h LockRank): it is refused at once, the other thread goes on, and
both end. Each case runs in a child process with a timeout, so a deadlock fails the test instead
of hanging the run. And a result read while another thread runs the job says the samples its
images hold (it said up to 9 for 1)."""

import pytest
from child import check_python

PROLOGUE = """
    import threading, time, bvhlab
    from bvhlab.library import showcase
    scene = showcase.whitted()
    bvh = bvhlab.build(scene)
    backend = {backend!r}
    renderer = bvhlab.Renderer(backend, **({{"validation": True}} if backend == "vulkan" else {{}}))
    renderer.render(scene, bvh, 32, 24)  # the scene uploaded
    out, first = {{}}, threading.Event()

    def both(a, b):
        threads = [threading.Thread(target=a, daemon=True), threading.Thread(target=b, daemon=True)]
        for t in threads:
            t.start()
        for t in threads:
            t.join(60)
        assert not any(t.is_alive() for t in threads), ("deadlocked", out)
"""


def _start_from_the_callable(backend: str) -> str:
    return (
        PROLOGUE.format(backend=backend)
        + """
    def progress(fraction):
        if not first.is_set():
            first.set()
            time.sleep(0.5)  # the other thread is inside renderer.start now
            try:
                renderer.start(scene, bvh, 16, 12)
                out["callable"] = "started"
            except RuntimeError as error:
                out["callable"] = str(error)

    def runs():
        renderer.start(scene, bvh, 160, 120, samples_per_axis=3, steps_per_dispatch=64).run(progress=progress)
        out["runs"] = "finished"

    def starts():
        first.wait()
        time.sleep(0.1)
        job = renderer.start(scene, bvh, 64, 48)
        job.run()
        out["starts"] = bool((job.result().depth < 1e10).any())

    both(runs, starts)
    assert out["runs"] == "finished" and out["starts"] is True, out
    if backend == "vulkan":
        assert "is inside a render's work" in out["callable"], out
        assert renderer.validation_errors == 0, renderer.validation_messages()
    else:  # the CPU tracer's run holds no renderer lock: nothing to wait for
        assert out["callable"] == "started", out
    print("ok")
"""
    )


def _read_another_job(backend: str, read: str) -> str:
    return (
        PROLOGUE.format(backend=backend)
        + f"""
    job1 = renderer.start(scene, bvh, 160, 120, samples_per_axis=3, steps_per_dispatch=64)
    job2 = renderer.start(scene, bvh, 64, 48)
    refused = []

    def progress(fraction):
        if not first.is_set():
            first.set()
            time.sleep(0.5)  # the other thread is in job2.run now
        try:
            job2.{read}
        except RuntimeError as error:
            refused.append(str(error))

    def runs():
        job1.run(progress=progress)
        out["job1"] = job1.done

    def runs_the_other():
        first.wait()
        time.sleep(0.1)
        job2.run()
        out["job2"] = job2.done

    both(runs, runs_the_other)
    assert out == {{"job1": True, "job2": True}}, out
    assert all("busy on another thread" in r for r in refused), refused
    if backend == "vulkan":
        assert refused, "job2 was busy while job1's run held the renderer"
        assert renderer.validation_errors == 0, renderer.validation_messages()
    print("ok")
"""
    )


@pytest.mark.parametrize("backend", ["cpu", "vulkan"])
def test_a_callable_starting_a_job_while_another_thread_starts_one(backend):
    assert check_python(_start_from_the_callable(backend), timeout=180).startswith("ok")


@pytest.mark.parametrize("read", ["samples_done", "timings", "result()"])
@pytest.mark.parametrize("backend", ["cpu", "vulkan"])
def test_a_callable_reading_a_job_another_thread_runs(backend, read):
    assert check_python(_read_another_job(backend, read), timeout=180).startswith("ok")


def test_a_result_read_while_another_thread_runs_says_the_samples_its_images_hold():
    program = """
        import threading
        import numpy as np, bvhlab
        from bvhlab.library import showcase
        scene = showcase.whitted()
        bvh = bvhlab.build(scene)
        renderer = bvhlab.Renderer("cpu")
        size = dict(samples_per_axis=3, threads=1)
        references = {}
        for n in range(1, 10):
            job = renderer.start(scene, bvh, 96, 72, **size)
            job.run(n)
            references[n] = job.result().color
        wrong, read = [], 0
        for repeat in range(40):  # reads fall between two runs: many sequences of them
            job = renderer.start(scene, bvh, 96, 72, **size)
            done = threading.Event()

            def runs():
                for n in range(1, 10):
                    job.run(n)
                done.set()

            thread = threading.Thread(target=runs)
            thread.start()
            while not done.is_set():
                r = job.result()
                read += 1
                if r.samples and not np.array_equal(r.color, references[r.samples]):
                    wrong.append(r.samples)
            thread.join()
        assert not wrong and read > 100, (wrong, read)
        print("ok", read)
    """
    assert check_python(program, timeout=300).startswith("ok")
