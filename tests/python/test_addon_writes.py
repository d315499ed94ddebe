"""Issue 39.8 in the add-on (bpy): Export stats and Compare's table go through bvhlab's atomic
writer. With no room to write (RLIMIT_FSIZE for this process, lowered around the one operator call:
writes past it fail with EFBIG, Python ignores SIGXFSZ), the operator reports an ERROR naming the
file and the old JSON and CSV keep their bytes."""

import contextlib
import resource

import blender_checks  # noqa: F401  (tests/blender on the import path)
import harness
import pytest


@pytest.fixture(scope="module", autouse=True)
def addon_enabled():
    harness.enable_addon_from_source()


@contextlib.contextmanager
def file_size_limit(size: int):
    soft, hard = resource.getrlimit(resource.RLIMIT_FSIZE)
    resource.setrlimit(resource.RLIMIT_FSIZE, (size, hard))
    try:
        yield
    finally:
        resource.setrlimit(resource.RLIMIT_FSIZE, (soft, hard))


def test_export_stats_without_room_keeps_the_old_files_and_names_them(tmp_path):
    import bpy

    harness.open_scene("five_spheres")
    assert bpy.ops.bvhlab.build() == {"FINISHED"}
    json_path, csv_path = tmp_path / "stats.json", tmp_path / "stats.csv"
    json_path.write_bytes(b'{"old": 1}')
    csv_path.write_bytes(b"metric,index,value\n")
    with file_size_limit(256), pytest.raises(RuntimeError) as report:
        bpy.ops.bvhlab.export_stats(filepath=str(json_path))
    assert f"cannot write {json_path}: File too large" in str(report.value)
    assert json_path.read_bytes() == b'{"old": 1}' and csv_path.read_bytes() == b"metric,index,value\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["stats.csv", "stats.json"]
    state = harness.addon().state
    assert state.messages[state.key(bpy.context.scene)] == ("ERROR", f"cannot write {json_path}: File too large")
    assert bpy.ops.bvhlab.export_stats(filepath=str(json_path)) == {"FINISHED"}  # with room again
    assert json_path.stat().st_size > 256 and csv_path.stat().st_size > 256


def test_compare_table_without_room_keeps_the_old_csv(tmp_path):
    """The Compare operator's CSV writer (bvhlab.compare.write_csv), fed rows as the operator does."""
    from bvhlab.compare import measure_methods, write_csv
    from bvhlab.library import load_scene
    from bvhlab.render import Renderer

    scene, _ = load_scene("gen:five_spheres")
    rows = measure_methods(scene, ["median"], frames=1, builds=1, width=8, height=8, renderer=Renderer("cpu"))
    path = tmp_path / "bvh_compare.csv"
    path.write_bytes(b"method\n")
    with file_size_limit(64), pytest.raises(OSError, match=f"cannot write {path}: File too large"):
        write_csv(rows, path)
    assert path.read_bytes() == b"method\n" and [p.name for p in tmp_path.iterdir()] == ["bvh_compare.csv"]
