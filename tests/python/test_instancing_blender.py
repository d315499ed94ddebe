"""Build and F12 on geometry-nodes instances and nested collection instances (tests/blender/
checks_instancing.py), each time in a child process: before issue 39's fix they segfaulted or hung
Blender in most runs (reading an instance's material slots after the depsgraph's instance iterator
had moved on: the material of every geometry-nodes instance was lost, read from freed memory)."""

from blender_checks import run_groups


def test_instances_build_and_render():
    done = run_groups("instancing", timeout=600)
    assert done.stdout.count("PASS instancing:") == 2, done.stdout[-2000:]
