"""`.blend` files as scenes (bvhlab.library.load_scene through bpy in a child process): a file
without a camera is framed by the default camera, as a mesh file is (it was refused: "has no
camera"), and the suffix is read in any case (S.BLEND was "no scene 'S.BLEND'")."""

import json
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]

MAKE = """
import sys, bpy
bpy.ops.wm.read_homefile(use_empty=True)
bpy.ops.mesh.primitive_cube_add(size=2.0, location=(1.0, 2.0, 3.0))
bpy.ops.wm.save_as_mainfile(filepath=sys.argv[1])
"""


def _run(args: list[str]) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, *args], capture_output=True, text=True, timeout=300, cwd=ROOT)


def test_a_blend_without_a_camera_builds_with_the_default_camera(tmp_path):
    blend = tmp_path / "NO_CAMERA.BLEND"
    made = _run(["-c", MAKE, str(blend)])
    assert made.returncode == 0, made.stderr[-2000:]
    out = tmp_path / "stats.json"
    done = _run(["-m", "bvhlab", "build", str(blend), "--json", str(out)])
    assert done.returncode == 0, done.stdout[-2000:] + done.stderr[-2000:]
    report = json.loads(out.read_text())
    assert report["stats"]["triangles"] == 12 and report["about"]["scene"] == "NO_CAMERA"
    assert "using a default camera that frames the geometry" in done.stderr
