"""Issue 39, hangs and unclear errors of the command line: bad arguments are refused with one line
saying what is wrong, before any work starts and before anything is written."""

import os
import subprocess
import sys

import pytest
from child import run_python

from bvhlab.compare import protocol


def run_cli(*args, timeout=60):
    done = subprocess.run(
        [sys.executable, "-m", "bvhlab", *map(str, args)], capture_output=True, text=True, timeout=timeout
    )
    return done.returncode, done.stdout, done.stderr


def last_line(stderr: str) -> str:
    assert "Traceback" not in stderr, stderr
    return stderr.strip().splitlines()[-1]


@pytest.mark.parametrize("option", ["--frames", "--builds"])
@pytest.mark.parametrize("count", ["99999999999999999999999", str(protocol.MAX_SAMPLES + 1)])
def test_compare_counts_have_an_upper_bound(tmp_path, option, count):
    """39.3: `--frames 99999999999999999999999` hung after the warm-up while RSS climbed 70-90 MB/s."""
    out = tmp_path / "never"
    code, _, err = run_cli("compare", "gen:five_spheres", option, count, "--out", out)
    assert code == 2 and last_line(err) == (
        f"bvhlab compare: error: argument {option}: must be at most {protocol.MAX_SAMPLES} "
        f"(more rounds no longer narrow the spread), got {count}"
    )
    assert not out.exists()


def test_rounds_are_made_one_at_a_time():
    """The rounds of a long measurement are not materialised up front (in a child under a 1 GiB
    address-space limit: a list of 10^12 rounds fails there at once with MemoryError)."""
    done = run_python(
        """
        import itertools, resource
        resource.setrlimit(resource.RLIMIT_AS, (1 << 30, resource.RLIM_INFINITY))
        from bvhlab.compare.protocol import rounds
        print(list(itertools.islice(rounds(["a", "b", "c"], 10**12), 4)))
        """,
        timeout=60,
    )
    assert done.stdout.strip() == "[['a', 'b', 'c'], ['b', 'c', 'a'], ['c', 'a', 'b'], ['a', 'b', 'c']]", done


def test_the_library_bounds_the_counts_too():
    import bvhlab
    from bvhlab.compare import measure_methods
    from bvhlab.library import load_scene

    scene, _ = load_scene("gen:five_spheres")
    for name in ("frames", "builds"):
        with pytest.raises(ValueError, match=f"{name} must be between 1 and {protocol.MAX_SAMPLES}, got 10001"):
            counts = {"frames": 5, "builds": 5, name: protocol.MAX_SAMPLES + 1}
            measure_methods(scene, ["median"], **counts, width=1, height=1, renderer=bvhlab.Renderer("cpu"))


@pytest.mark.parametrize(
    "args, name",
    [
        (["render", "gen:five_spheres", "--out", "{d}/.png"], ".png"),
        (["snapshot", "gen:five_spheres", "--out", "{d}/.PNG"], ".PNG"),
        (["build", "gen:five_spheres", "--json", "{d}/.json"], ".json"),
        (["build", "gen:five_spheres", "--csv", "{d}/.csv"], ".csv"),
    ],
)
def test_an_output_name_without_a_stem_is_named_so(tmp_path, args, name):
    """`--out .png` used to say "a PNG image is written as .png; name the file so (e.g. .png.png)"."""
    code, _, err = run_cli(*[a.format(d=tmp_path) for a in args])
    assert code == 2 and last_line(err).endswith(
        f"{tmp_path}/{name}: the file name has no stem, only the suffix; name the file, e.g. {tmp_path}/out{name}"
    ), err
    assert os.listdir(tmp_path) == []


@pytest.mark.parametrize("command, name", [("build", "s.npz"), ("render", "s.BLEND"), ("compare", "s.Obj")])
def test_a_fifo_as_the_scene_is_refused_without_hanging(tmp_path, command, name):
    """Opening a FIFO blocks until a writer comes: the CLI used to hang, then said "not an .npz";
    a suffix in upper case (s.BLEND, which the loader reads as a .blend) still hung (probe)."""
    fifo = tmp_path / name
    os.mkfifo(fifo)
    extra = {"build": [], "render": ["--out", tmp_path / "r.png"], "compare": ["--out", tmp_path / "c"]}[command]
    code, _, err = run_cli(command, fifo, *extra, timeout=30)
    assert code == 2 and last_line(err) == (
        f"bvhlab {command}: error: argument SCENE: {fifo} is not a regular file (a FIFO, device or "
        f"socket); give a scene file (.blend, .npz, .obj, .ply, .stl, .gltf, .glb)"
    )
    assert os.listdir(tmp_path) == [name]


@pytest.mark.parametrize(
    "name, call, error, what",
    [
        # load_bvh read a FIFO whole (and `bvhlab inspect --tree FIFO` waited with it)
        ("t.bvhtree", "bvhlab.load_bvh({path!r}, np.zeros((1, 3, 3), np.float32))", "TreeFileError", "a tree file"),
        ("s.npz", "bvhlab.Scene.load({path!r})", "SceneFileError", "a scene file"),
        # load_scene of a .blend blocked in bpy's open (probe: the CLI's upper-case case reached it)
        ("s.blend", "bvhlab.library.load_scene({path!r})", "SceneFileError", "a .blend file"),
        ("s.ply", "bvhlab.library.load_scene({path!r})", "SceneFileError", "a mesh file"),
    ],
)
def test_a_fifo_is_refused_by_every_reader_without_hanging(tmp_path, name, call, error, what):
    """Opening a FIFO blocks until a writer comes: each reader refuses one first (_checks.input_file)."""
    fifo = tmp_path / name
    os.mkfifo(fifo)
    done = run_python(
        f"""
        import numpy as np
        import bvhlab
        import bvhlab.library
        try:
            {call.format(path=str(fifo))}
        except ValueError as e:
            print(type(e).__name__, e)
        """,
        timeout=60,
    )
    assert done.stdout.strip() == f"{error} {fifo} is not a regular file (a FIFO, device or socket), not {what}"


def test_compare_refuses_a_bad_method_setting_before_any_work(tmp_path):
    """`--methods sah1` was refused only after the scene was loaded and the measurement started
    ("bins must be between 2 and 256, got 1"): now by argparse, with build's own message."""
    out = tmp_path / "never"
    code, stdout, err = run_cli("compare", "gen:five_spheres", "--methods", "median,sah1", "--out", out)
    assert code == 2 and last_line(err) == (
        "bvhlab compare: error: argument --methods: sah1: bins must be between 2 and 256, got 1"
    )
    assert "building" not in err and stdout == "" and not out.exists()


@pytest.mark.parametrize(
    "args, message",
    [
        (["--method", "sah1"], "bins must be between 2 and 256, got 1"),
        (["--bins", "300"], "argument --bins: must be between 2 and 256, got 300"),
        (["--max-leaf-size", "0"], "argument --max-leaf-size: must be between 1 and 2147483647, got 0"),
        (["--max-leaf-size", "4.5"], "argument --max-leaf-size: expected a whole number, got '4.5'"),
        (["--sah-block", "3"], "argument --sah-block: must be a power of two from 1 to 64, got 3"),
        (["--sah-block", "128"], "argument --sah-block: must be a power of two from 1 to 64, got 128"),
    ],
)
@pytest.mark.parametrize("command", ["build", "render"])
def test_build_settings_are_checked_before_the_scene_is_read(tmp_path, command, args, message):
    """The settings are refused before the scene is loaded: here the scene does not even exist, and
    the error is about the setting, not the file."""
    extra = ["--out", tmp_path / "r.png"] if command == "render" else []
    code, _, err = run_cli(command, tmp_path / "missing.npz", *args, *extra)
    assert code == 2 and last_line(err) == f"bvhlab {command}: error: {message}"


def test_snapshot_sheet_and_depth_range_are_alternatives(tmp_path):
    """The usage offers `--bvh-depth A:B | --sheet`; both used to be accepted (the range ignored)."""
    code, _, err = run_cli("snapshot", "gen:five_spheres", "--sheet", "--bvh-depth", "1:2", "--out", tmp_path / "s.png")
    assert (
        code == 2
        and last_line(err) == "bvhlab snapshot: error: argument --bvh-depth: not allowed with argument --sheet"
    )
    assert os.listdir(tmp_path) == []


def test_the_interval_of_the_largest_count_is_the_exact_one():
    """The order statistic of the median's interval, carried from k to k: the same as the
    definition (math.comb each step) wherever that is quick, and at MAX_SAMPLES where the normal
    approximation puts it (n/2 - 1.645·√n/2), which the old way took 15 s to reach."""
    import math

    def by_definition(n):
        best, below = None, 0.0
        for k in range(1, n // 2 + 1):
            below += math.comb(n, k - 1) / 2**n
            if 1 - 2 * below < protocol.CONFIDENCE:
                break
            best = k
        return best

    assert all(protocol._order_rank(n) == by_definition(n) for n in range(1, 400))
    n = protocol.MAX_SAMPLES
    assert abs(protocol._order_rank(n) - (n / 2 - 1.6449 * math.sqrt(n) / 2)) < 1.5


@pytest.mark.parametrize(
    "args",
    [
        ("animate", "wave", "--size", "10", "--frames", "0-1", "--out", "/proc/bvhlab_animate"),
        ("build", "gen:five_spheres", "--json", "/proc/bvhlab_stats.json"),
        ("inspect", "gen:five_spheres", "--node", "0", "--json", "/proc/bvhlab_inspect.json"),
        ("compare", "gen:five_spheres", "--out", "/proc/bvhlab_compare"),
        ("render", "gen:five_spheres", "--out", "/proc/bvhlab.png"),
    ],
)
def test_an_output_where_no_file_can_be_made_is_refused_before_the_work(args):
    """The probe's case: an output under /proc or /sys (or a read-only mount) was refused only when
    written, after the work (a whole animation experiment); the folder is tried first, by making a
    file there and deleting it (permissions alone say nothing of such folders, or to root)."""
    code, out, err = run_cli(*args)
    assert code == 2 and "does not take new files" in last_line(err), err
    assert out == ""  # nothing ran: no progress, no table


@pytest.mark.parametrize("side", ["c.npy", "c.histogram.png", "c.histogram.json"])
def test_render_counter_checks_the_files_beside_out_before_any_work(tmp_path, side):
    """The probe's case: a folder named as one of the files `render --counter` writes beside OUT
    (the counts, the histogram) was found after the render, with OUT written and the rest not."""
    (tmp_path / side).mkdir()
    code, stdout, err = run_cli(
        "render", "gen:five_spheres", "--width", 16, "--height", 12, "--backend", "cpu", "--counter", "box_tests",
        "--out", tmp_path / "c.png",
    )  # fmt: skip
    assert code == 2 and last_line(err).startswith(f"bvhlab render: error: {tmp_path / side} is a folder")
    assert "building" not in err and stdout == "" and sorted(os.listdir(tmp_path)) == [side]


@pytest.mark.parametrize(
    "args, message",
    [
        (["render", "gen:five_spheres", "--counter", "box_tests", "--film-transparent", "--out", "{d}/r.png"],
         "--film-transparent is for the shaded image"),
        (["render", "gen:five_spheres", "--counter", "box_tests", "--bvh-depth", "0:3", "--out", "{d}/r.png"],
         "--bvh-depth draws boxes over the shaded image"),
        (["compare", "gen:five_spheres", "--counter", "prim_hits", "--out", "{d}/c"],
         "--counter is the counter of --counter-diff A,B"),
        (["animate", "{blend}", "--size", "7", "--out", "{d}/a"], "--size sizes the generated animations"),
        (["animate", "wave", "--width", "64", "--out", "{d}/a"], "--width and --height size the traced frames"),
    ],
)  # fmt: skip
def test_options_that_would_be_ignored_are_refused(tmp_path, args, message):
    """The probes' cases, each accepted and ignored: a counter's image with --film-transparent or
    --bvh-depth came out byte for byte the same, compare --counter without --counter-diff ran the whole comparison,
    animate --size on a .blend was written into animate.json as if used."""
    from bvhlab.library import bundled_dir

    blend = next(bundled_dir().glob("*.blend"))
    code, stdout, err = run_cli(*(a.format(d=tmp_path, blend=blend) for a in args))
    assert code == 2 and message in last_line(err), err
    assert "building" not in err and os.listdir(tmp_path) == []


def test_sweep_refuses_a_fifo_spec_without_hanging(tmp_path):
    """`bvhlab sweep FIFO` blocked until a writer came (review)."""
    fifo = tmp_path / "spec.toml"
    os.mkfifo(fifo)
    code, _, err = run_cli("sweep", fifo, "--out", tmp_path / "out", timeout=30)
    assert code == 2 and last_line(err) == (
        f"bvhlab sweep: error: {fifo} is not a regular file (a FIFO, device or socket), not a sweep spec"
    )


@pytest.mark.parametrize("closed", [1, 2])
def test_a_closed_stdout_or_stderr_loses_nothing(tmp_path, closed):
    """Started with stdout or stderr closed (`>&-`, `2>&-`, as cron and daemons run), Python has no
    sys.stdout or sys.stderr: every command failed with 1, a traceback or nothing, and wrote nothing
    (a helper's audit). It does its work now; what it would print goes nowhere."""
    out = tmp_path / "stats.json"
    done = subprocess.run(
        [sys.executable, "-m", "bvhlab", "build", "gen:five_spheres", "--json", str(out)],
        preexec_fn=lambda: os.close(closed),
        stdout=subprocess.DEVNULL if closed == 2 else None,
        stderr=subprocess.DEVNULL if closed == 1 else None,
        timeout=120,
    )
    assert done.returncode == 0 and out.stat().st_size > 0
