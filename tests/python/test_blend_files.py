"""`.blend` files as scenes (bvhlab.library.load_scene through bpy in a child process): a file
without a camera is framed by the default camera, as a mesh file is (it was refused: "has no
camera"), and the suffix is read in any case (S.BLEND was "no scene 'S.BLEND'")."""

import json
import subprocess
import sys
from pathlib import Path

import pytest
from child import default_sigint

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


LIBRARY = """
import sys, bpy
bpy.ops.wm.read_homefile(use_empty=True)
if sys.argv[2] == "cube":
    bpy.ops.mesh.primitive_cube_add(size=2.0)
else:
    bpy.ops.mesh.primitive_ico_sphere_add(subdivisions=1)
bpy.context.object.name = "Part"
bpy.context.object.data.name = "Part mesh"  # one name for both shapes: a duplicate linking it keeps it
bpy.ops.wm.save_as_mainfile(filepath=sys.argv[1])
"""

LINKING = """
import sys, bpy
bpy.ops.wm.read_homefile(use_empty=True)
with bpy.data.libraries.load(sys.argv[2], link=True) as (source, linked):
    linked.objects = ["Part"]
part = linked.objects[0]
bpy.context.scene.collection.objects.link(part)
if sys.argv[3] == "twice":  # a linked duplicate of it beside it: the export's instances of one mesh
    copy = bpy.data.objects.new("Copy", part.data)
    copy.location = (3.0, 0.0, 0.0)
    bpy.context.scene.collection.objects.link(copy)
bpy.ops.wm.save_as_mainfile(filepath=sys.argv[1])
"""

MOVE = """
import sys, bpy
bpy.ops.wm.open_mainfile(filepath=sys.argv[1])
bpy.data.objects["Copy"].location.x += 2.0
bpy.ops.wm.save_mainfile()
"""

SWEEP = """
import json, sys
from bvhlab.sweep import read_spec, run_sweep
result = run_sweep(read_spec(sys.argv[1]), sys.argv[2], plot=False)
print(json.dumps({"ran": result.ran, "triangles": [row["triangles"] for row in result.rows]}))
"""


@pytest.mark.parametrize("copies", ["once", "twice"])
def test_a_sweep_of_a_blend_sees_its_linked_library_change(tmp_path, copies):
    """A .blend whose mesh is linked from another file (once, or twice: two instances of one mesh):
    the library edited, the sweep measures the new mesh (its cells were keyed by the .blend's bytes
    alone: the old figures came back; then by the arrays of its own mesh alone, which an instanced
    mesh is not)."""
    library, scene = tmp_path / "library.blend", tmp_path / "scene.blend"
    for args in ([LIBRARY, str(library), "cube"], [LINKING, str(scene), str(library), copies]):
        made = _run(["-c", *args])
        assert made.returncode == 0, made.stderr[-2000:]
    spec = tmp_path / "spec.toml"
    spec.write_text(f'scenes = ["{scene}"]\n[grid]\nmethod = "sah"\n[rays]\ncount = 500\n')

    def sweep() -> dict:
        done = _run(["-c", SWEEP, str(spec), str(tmp_path / "out")])
        assert done.returncode == 0, done.stdout[-2000:] + done.stderr[-2000:]
        return json.loads(done.stdout.strip().splitlines()[-1])

    # (two copies: one mesh stored once, its triangles counted once)
    assert sweep() == {"ran": 1, "triangles": [12]}
    assert sweep() == {"ran": 0, "triangles": [12]}  # nothing changed: nothing run again
    if copies == "twice":  # the duplicate moved: its instance's transform (the mesh's arrays alike)
        made = _run(["-c", MOVE, str(scene)])
        assert made.returncode == 0, made.stderr[-2000:]
        assert sweep() == {"ran": 1, "triangles": [12]}
    made = _run(["-c", LIBRARY, str(library), "ico"])
    assert made.returncode == 0, made.stderr[-2000:]
    assert sweep() == {"ran": 1, "triangles": [20]}  # an icosahedron


def test_a_blend_whose_linked_library_is_missing_is_refused(tmp_path):
    """Blender opens it with the linked mesh left out and says so on stderr only: a build counted
    the file's own triangles and exited 0, a sweep's row said "ok" (a helper's probe)."""
    library, scene = tmp_path / "library.blend", tmp_path / "scene.blend"
    for args in ([LIBRARY, str(library), "cube"], [LINKING, str(scene), str(library), "once"]):
        made = _run(["-c", *args])
        assert made.returncode == 0, made.stderr[-2000:]
    library.unlink()
    done = _run(["-m", "bvhlab", "build", str(scene)])
    assert done.returncode == 2, done.stdout[-2000:] + done.stderr[-2000:]
    assert "links 1 .blend library that is missing: //library.blend" in done.stderr


RENAME = """
import sys, bpy
bpy.ops.wm.open_mainfile(filepath=sys.argv[1])
bpy.data.objects["Part"].name = "Renamed"
bpy.ops.wm.save_mainfile()
"""


def test_a_blend_whose_library_lost_the_linked_object_is_refused(tmp_path):
    """The library is there but the object linked from it was renamed: Blender leaves it out and
    says so on stderr only (the review: 20 triangles for 32, exit 0)."""
    library, scene = tmp_path / "library.blend", tmp_path / "scene.blend"
    for args in ([LIBRARY, str(library), "cube"], [LINKING, str(scene), str(library), "once"], [RENAME, str(library)]):
        made = _run(["-c", *args])
        assert made.returncode == 0, made.stderr[-2000:]
    done = _run(["-m", "bvhlab", "build", str(scene)])
    assert done.returncode == 2, done.stdout[-2000:] + done.stderr[-2000:]
    assert "links data its library no longer holds: object 'Part' from //library.blend" in done.stderr


def test_a_blend_saved_by_a_newer_blender_says_so(tmp_path):
    """bpy 4.2 reads Blender 5.0's file format as "not a blend file": the header names the Blender
    that saved it (a file of that header and nothing after it; the bpy of this test is older)."""
    from bvhlab.blender.load import saved_by_version

    newer = tmp_path / "newer.blend"
    newer.write_bytes(b"BLENDER17-01v9900" + bytes(64))
    assert saved_by_version(newer) == (99, 0)
    done = _run(["-m", "bvhlab", "build", str(newer)])
    assert done.returncode == 2 and "it was saved by Blender 99.0, newer than this bpy" in done.stderr, done.stderr
    for head, version in ((b"BLENDER-v402REND", (4, 2)), (b"BLENDER_V293", (2, 93)), (b"\x28\xb5\x2f\xfd", None)):
        newer.write_bytes(head + bytes(16))
        assert saved_by_version(newer) == version, head


SAVED_DISTANCE = """
import sys, bpy
bpy.ops.wm.read_homefile(use_empty=True)
bpy.ops.mesh.primitive_cube_add(size=2.0)
bpy.ops.object.light_add(type="POINT", location=(0.0, 0.0, 6.0))
bpy.context.active_object.data.energy = 1000.0
if float(sys.argv[2]) > 0:  # the add-on's settings group as it registers it, set, then saved
    class Settings(bpy.types.PropertyGroup):
        light_distance: bpy.props.FloatProperty(default=0.0)
    bpy.utils.register_class(Settings)
    bpy.types.Scene.bvhlab = bpy.props.PointerProperty(type=Settings)
    bpy.context.scene.bvhlab.light_distance = float(sys.argv[2])
bpy.ops.wm.save_as_mainfile(filepath=sys.argv[1])
"""
READ_LIGHT = """
import sys
from pathlib import Path
from bvhlab.blender.load import load_blend
print(repr(load_blend(Path(sys.argv[1])).light.intensity))
"""


def test_a_blend_is_lit_by_its_saved_light_distance(tmp_path):
    """The add-on's Light Distance saved in a .blend lights it in the CLI too (`bvhlab render
    FILE.blend` measured the distance again: another intensity than F12's); unset, it is measured.
    Read by a bpy without the add-on, from the values Blender keeps for the unregistered group."""
    from bvhlab.blender.light import intensity_from_watts

    intensities = {}
    for distance in (0.0, 4.5):
        blend = tmp_path / f"lit_{distance}.blend"
        made = _run(["-c", SAVED_DISTANCE, str(blend), str(distance)])
        assert made.returncode == 0, made.stderr[-2000:]
        read = _run(["-c", READ_LIGHT, str(blend)])
        assert read.returncode == 0, read.stderr[-2000:]
        intensities[distance] = float(read.stdout.strip().splitlines()[-1])
    assert intensities[4.5] == intensity_from_watts(1000.0, 4.5)
    assert intensities[0.0] != intensities[4.5]  # measured: the cube's faces lie 5 to 7 from the light


#: Ctrl-C (a SIGINT from a timer) `delay` seconds into Blender's module loading (~0.3 s: its
#: add-ons enabled, which print and swallow a KeyboardInterrupt).
CTRL_C_WHILE_BPY_LOADS = """
import os, signal, sys
import bvhlab
signal.signal(signal.SIGALRM, lambda *_: os.kill(os.getpid(), signal.SIGINT))
signal.setitimer(signal.ITIMER_REAL, float(sys.argv[1]))
try:
    import bvhlab.blender
    print("imported")
except KeyboardInterrupt:
    print("KeyboardInterrupt")
"""


@pytest.mark.parametrize("delay", [0.05, 0.2])
def test_ctrl_c_while_blender_loads_is_raised(delay):
    # it was lost in bpy's loading (every command with a .blend scene ran on and exited 0)
    got = subprocess.run(
        [sys.executable, "-c", CTRL_C_WHILE_BPY_LOADS, str(delay)],
        capture_output=True,
        text=True,
        timeout=300,
        preexec_fn=default_sigint,
    )
    assert got.stdout.strip() == "KeyboardInterrupt", (got.stdout, got.stderr[-2000:])
