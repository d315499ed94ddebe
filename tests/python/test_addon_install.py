"""The extension zip that scripts/build_addon.py makes installs and enables headless, unregisters
without leftovers, and enables again (in a child process with its own user folder)."""
import subprocess
import sys
from pathlib import Path

import blender_checks

ROOT = Path(__file__).resolve().parents[2]


def test_built_zip_installs_enables_and_unregisters(tmp_path):
    built = subprocess.run([sys.executable, str(ROOT / "scripts" / "build_addon.py"), "--output-dir", str(tmp_path)],
                           capture_output=True, text=True, timeout=900)
    assert built.returncode == 0, built.stdout[-3000:] + built.stderr[-3000:]
    zip_path = Path(built.stdout.strip().splitlines()[-1])
    assert zip_path.parent == tmp_path and zip_path.suffix == ".zip"
    blender_checks.run_groups("install", zip_path=zip_path)
