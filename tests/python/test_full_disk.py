"""Issue 39.8 on a real full disk (a filled tmpfs, see full_disk.py): `render --out`, `build
--json/--csv`, `compare`, `snapshot --sheet`, Scene.save and the charts each fail with one line
naming the file, leave the old file byte for byte, and leave no temporary on the disk. The same
under a file-size limit (RLIMIT_FSIZE), a second way that needs no mount."""

import sys

import numpy as np
import pytest
from cli_args import QUICK_COMPARE
from full_disk import full_disk_unavailable, run_on_full_disk

import bvhlab
from bvhlab.library import load_scene

needs_mount = pytest.mark.skipif(full_disk_unavailable() is not None, reason=str(full_disk_unavailable()))

FULL = "No space left on device"


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    """A small scene and a small old PNG (a few hundred bytes) to put on the disk."""
    d = tmp_path_factory.mktemp("full_disk_inputs")
    scene, _ = load_scene("gen:five_spheres")
    scene.save(d / "s.npz")
    bvhlab.save_png(np.full((4, 4, 3), 0.5, np.float32), d / "good.png")
    return {"s.npz": (d / "s.npz").read_bytes(), "good.png": (d / "good.png").read_bytes()}


def _cli(*args):
    return [sys.executable, "-m", "bvhlab", *args]


def _assert_kept(result, name: str, old: bytes, command: str):
    """Exit 2, one error line naming the file, the old bytes kept, nothing else left behind."""
    assert result["code"] == 2, result
    last = result["stderr"].strip().splitlines()[-1]
    assert "Traceback" not in result["stderr"]
    assert (
        last.startswith(f"bvhlab {command}: error: ")
        and f"cannot write {{disk}}/{name}: {FULL}".replace("{disk}", result["disk"]) in last
    ), result["stderr"]
    assert result["files"][name]["data"] == old


def _run(tmp_path, command, setup, size_kb=256):
    result = run_on_full_disk(tmp_path / "disk", command, setup, size_kb)
    result["disk"] = str(tmp_path / "disk")
    return result


@needs_mount
def test_render_keeps_the_old_png(tmp_path, files):
    """The issue's case: the old PNG used to be left as a truncated 4,096-byte file (the new one,
    about 20 KB, does not fit in the page the truncated old one gave back)."""
    setup = {"s.npz": files["s.npz"], "tiny/good.png": files["good.png"]}
    result = _run(
        tmp_path,
        _cli(
            "render",
            "{disk}/s.npz",
            "--out",
            "{disk}/tiny/good.png",
            "--width",
            "320",
            "--height",
            "240",
            "--backend",
            "cpu",
        ),
        setup,
    )
    _assert_kept(result, "tiny/good.png", files["good.png"], "render")
    assert sorted(result["files"]) == ["s.npz", "tiny/good.png"]


@needs_mount
@pytest.mark.parametrize("option, name", [("--json", "stats.json"), ("--csv", "stats.csv")])
def test_build_keeps_the_old_stats_file(tmp_path, files, option, name):
    """`build --json` used to leave an empty JSON."""
    old = b'{"about": {}, "stats": {}}\n' if name.endswith("json") else b"metric,index,value\n"
    result = _run(
        tmp_path, _cli("build", "{disk}/s.npz", option, f"{{disk}}/{name}"), {"s.npz": files["s.npz"], name: old}
    )
    _assert_kept(result, name, old, "build")
    assert sorted(result["files"]) == sorted(["s.npz", name])


@needs_mount
def test_compare_keeps_the_old_table(tmp_path, files):
    """`compare` used to leave an empty table.csv. It measures, then fails at its first file."""
    old = b"method,frame_ms\nmedian,41.8\n"
    command = _cli(
        "compare",
        "{disk}/s.npz",
        *QUICK_COMPARE,
        "--out",
        "{disk}/out",
    )
    result = _run(tmp_path, command, {"s.npz": files["s.npz"], "out/table.csv": old})
    _assert_kept(result, "out/table.csv", old, "compare")
    assert sorted(result["files"]) == ["out/table.csv", "s.npz"]  # no temporary, no lock file


@needs_mount
def test_snapshot_sheet_keeps_the_old_png(tmp_path, files):
    """The sheet is drawn and saved (matplotlib) in a child process; its error comes back named."""
    pytest.importorskip("moderngl")
    setup = {"s.npz": files["s.npz"], "sheet.png": files["good.png"]}
    result = _run(tmp_path, _cli("snapshot", "{disk}/s.npz", "--sheet", "--out", "{disk}/sheet.png"), setup)
    if "no headless OpenGL" in result["stderr"]:
        pytest.skip(result["stderr"].strip())
    _assert_kept(result, "sheet.png", files["good.png"], "snapshot")
    assert sorted(result["files"]) == ["s.npz", "sheet.png"]


@needs_mount
def test_scene_save_keeps_the_old_file(tmp_path, files):
    """Scene.save (also what the Blender export writes) raises a WriteError naming the file."""
    code = """
        import sys, bvhlab
        from bvhlab.library import procedural
        scene = bvhlab.Scene(triangles=procedural.random_triangles(20000, seed=3))
        try:
            scene.save("{disk}/s.npz")
        except OSError as e:
            print(type(e).__name__, e, file=sys.stderr)
            sys.exit(2)
    """
    result = _run(tmp_path, [sys.executable, "-c", code.replace("\n        ", "\n").strip()], {"s.npz": files["s.npz"]})
    assert result["code"] == 2 and f"WriteError cannot write {result['disk']}/s.npz: {FULL}" in result["stderr"]
    assert result["files"]["s.npz"]["data"] == files["s.npz"]
    assert sorted(result["files"]) == ["s.npz"]


@needs_mount
def test_a_chart_keeps_the_old_png(tmp_path, files):
    """matplotlib's savefig goes through the same writer (compare's charts)."""
    code = """
        import sys
        from bvhlab.compare import charts
        rows = [{"method": m, "nodes_per_depth": [1, 2, 4, 8, 16, 32]} for m in ("median", "sah12")]
        try:
            charts.nodes_per_depth_chart(rows, "{disk}/nodes.png", "a title")
        except OSError as e:
            print(type(e).__name__, e, file=sys.stderr)
            sys.exit(2)
    """
    result = _run(
        tmp_path, [sys.executable, "-c", code.replace("\n        ", "\n").strip()], {"nodes.png": files["good.png"]}
    )
    assert result["code"] == 2 and f"WriteError cannot write {result['disk']}/nodes.png: {FULL}" in result["stderr"]
    assert result["files"]["nodes.png"]["data"] == files["good.png"]
    assert sorted(result["files"]) == ["nodes.png"]


@pytest.mark.parametrize("option, name", [("--json", "stats.json"), ("--csv", "stats.csv")])
def test_build_under_a_file_size_limit_keeps_the_old_stats_file(tmp_path, files, option, name):
    """Writes past RLIMIT_FSIZE fail with EFBIG (Python ignores SIGXFSZ): `build --json` used to
    leave the first 256 bytes of the new file in place of the old one."""
    import resource
    import subprocess

    old = b'{"about": {}, "stats": {}}\n' if name.endswith("json") else b"metric,index,value\n"
    (tmp_path / "s.npz").write_bytes(files["s.npz"])
    (tmp_path / name).write_bytes(old)
    done = subprocess.run(
        _cli("build", tmp_path / "s.npz", option, tmp_path / name),
        capture_output=True,
        text=True,
        timeout=120,
        preexec_fn=lambda: resource.setrlimit(resource.RLIMIT_FSIZE, (256, resource.RLIM_INFINITY)),
    )
    assert done.returncode == 2 and done.stderr.strip().splitlines()[-1] == (
        f"bvhlab build: error: cannot write {tmp_path / name}: File too large"
    ), done.stderr
    assert (tmp_path / name).read_bytes() == old
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(["s.npz", name])
