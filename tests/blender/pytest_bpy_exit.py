"""pytest plugin (pyproject: -p pytest_bpy_exit): once bpy has been imported, end the process with
pytest's exit status right after its summary instead of running the interpreter's teardown, where
bpy 4.2 as a module segfaults (after the add-on has been enabled and used in the process; the same
teardown crash tests/blender/run.py avoids). Every test has run and been reported by then."""

import os
import sys


def pytest_sessionfinish(session, exitstatus):
    session.config.stash_bpy_exit = int(exitstatus)


def pytest_unconfigure(config):
    if "bpy" in sys.modules and hasattr(config, "stash_bpy_exit"):
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(config.stash_bpy_exit)
