"""Build and F12 on geometry-nodes instances and nested collection instances (tests/blender/
checks_instancing.py), each time in a child process: before issue 39's fix they segfaulted or hung
Blender in most runs (reading an instance's material slots after the depsgraph's instance iterator
had moved on), so the group runs twice."""

import pytest
from blender_checks import run_groups


@pytest.mark.parametrize("run", [1, 2])
def test_instances_build_and_render(run):
    done = run_groups("instancing", timeout=600)
    assert done.stdout.count("PASS instancing:") == 2, done.stdout[-2000:]
