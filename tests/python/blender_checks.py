"""Puts tests/blender (the checks shared with tests/blender/run.py) on the import path, and runs
checks of tests/blender/registry.py in a child process (registry.CHILD_GROUPS says which and why)."""

import os
import re
import subprocess
import sys
from pathlib import Path

BLENDER_TESTS = Path(__file__).resolve().parents[1] / "blender"
sys.path.insert(0, str(BLENDER_TESTS))
ROOT = BLENDER_TESTS.parents[1]
#: `make check` sets BVHLAB_ZIP to a zip with the cp311 wheel alone (no Debian roots needed) and
#: deselects the tests marked full_zip, which need every Python's wheel.
ZIP = Path(os.environ.get("BVHLAB_ZIP") or ROOT / "dist" / "bvhlab.zip")

_OUTCOME = re.compile(r"^(PASS|FAIL|SKIP) (\S+)")


def run_in_child(ids: list[str], zip_path: Path | None = None, timeout: int = 600) -> dict[str, tuple[str, str]]:
    """tests/blender/run.py --only IDS in one child Python with bpy: check id → (PASS, FAIL or SKIP,
    its output and traceback). A check the child never reached (it died or ran out of time) is
    a FAIL with the end of the child's output."""
    command = [sys.executable, str(BLENDER_TESTS / "run.py"), "--only", *ids]
    if zip_path is not None:
        command += ["--zip", str(zip_path)]
    try:
        done = subprocess.run(command, capture_output=True, text=True, timeout=timeout)
        stdout, stderr, ending = done.stdout, done.stderr, f"exit status {done.returncode}"
    except subprocess.TimeoutExpired as expired:
        stdout, stderr = (expired.stdout or b"").decode(), (expired.stderr or b"").decode()
        ending = f"still running after {timeout} s"
    outcomes, lines = {}, []
    for line in stdout.splitlines():
        match = _OUTCOME.match(line)
        if match and match.group(2) in ids:
            outcomes[match.group(2)] = (match.group(1), "\n".join(lines + [line]))
            lines = []
        else:
            lines.append(line)
    for missing in set(ids) - set(outcomes):
        said = f"run.py --only {' '.join(ids)}: {ending} before {missing} reported"
        outcomes[missing] = ("FAIL", f"{said}:\n{stdout[-6000:]}\n{stderr[-3000:]}")
    return outcomes
