"""Puts tests/blender (the checks shared with tests/blender/run.py) on the import path, and runs
groups of them in a child process (Blender aborts the process on GPU failures)."""

import os
import subprocess
import sys
from pathlib import Path

BLENDER_TESTS = Path(__file__).resolve().parents[1] / "blender"
sys.path.insert(0, str(BLENDER_TESTS))


def run_groups(*groups: str, zip_path=None, env=None, timeout: int = 300) -> subprocess.CompletedProcess:
    """tests/blender/run.py --only GROUPS in a child Python with bpy; fails with its output."""
    command = [sys.executable, str(BLENDER_TESTS / "run.py"), "--only", *groups]
    if zip_path is not None:
        command += ["--zip", str(zip_path)]
    done = subprocess.run(command, capture_output=True, text=True, timeout=timeout, env={**os.environ, **(env or {})})
    assert done.returncode == 0, (
        f"run.py --only {' '.join(groups)} failed:\n{done.stdout[-6000:]}\n{done.stderr[-3000:]}"
    )
    return done
