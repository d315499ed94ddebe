"""A render job's progress callable that calls back into the job or its renderer (issue 39): the
reads that are safe there work, everything else raises RuntimeError at once. Before, each of these
deadlocked (the job held its lock while the callable ran) and ignored Ctrl-C; each case runs in a
child process with a timeout, so a deadlock fails the test instead of hanging the run."""

import pytest
from child import check_python

CASES = {
    # (what the callable does, what must happen)
    "samples_done": ("seen.append(job.samples_done)", "works"),
    "timings": ("seen.append(job.timings['backend'])", "works"),
    "result": ("job.result()", "refused"),
    "run": ("job.run(1)", "refused"),
    "start_on_same_renderer": ("renderer.start(scene, bvh, 32, 24).run()", "vulkan_refused"),
}


def _program(backend: str, call: str, expect: str) -> str:
    return f"""
        import bvhlab
        from bvhlab.library import showcase
        scene = showcase.whitted()
        bvh = bvhlab.build(scene)
        renderer = bvhlab.Renderer({backend!r}, **({{"validation": True}} if {backend!r} == "vulkan" else {{}}))
        job = renderer.start(scene, bvh, 64, 48, samples_per_axis=2)
        seen, errors = [], []

        def progress(fraction):
            try:
                {call}
            except RuntimeError as error:
                errors.append(str(error))
                raise

        expect = {expect!r}
        if expect == "vulkan_refused":
            expect = "refused" if renderer.backend == "vulkan" else "works"
        try:
            job.run(progress=progress)
            outcome = "works"
        except RuntimeError as error:
            outcome = "refused"
            assert "busy on this thread" in str(error), error
            assert errors and errors[0] == str(error), (errors, error)
        assert outcome == expect, (outcome, expect, errors)
        if outcome == "works":
            assert job.done and seen or {call!r}.startswith("renderer."), seen
            if seen and isinstance(seen[0], int):
                # during the run: the samples of the runs before (0); the last call, after it: all
                # (a run can finish before its first poll: then only the last call is seen)
                assert seen == sorted(seen) and set(seen) <= {{0, job.samples_per_pixel}}, seen
                assert seen[-1] == job.samples_per_pixel, seen
            assert (job.result().depth < 1e10).any()  # whitted: the floor and spheres are hit
        else:
            # the job is usable afterwards: finish it and check it rendered something
            job.run()
            assert job.done and (job.result().depth < 1e10).any()
        if renderer.backend == "vulkan":
            assert renderer.validation_errors == 0, renderer.validation_messages()
        print("ok", outcome)
    """


@pytest.mark.parametrize("backend", ["cpu", "vulkan"])
@pytest.mark.parametrize("case", list(CASES))
def test_progress_callable_calling_back_into_its_job(backend, case):
    call, expect = CASES[case]
    out = check_python(_program(backend, call, expect), timeout=120)
    assert out.startswith("ok")
