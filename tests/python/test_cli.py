"""The bvhlab command line end to end: each subcommand, exit codes, files written and parseable,
and numbers equal to the Python API's for the same builds."""

import csv
import json
import struct
import subprocess
import sys

import numpy as np
import pytest
from png_reader import read_png

import bvhlab
from bvhlab import legend
from bvhlab.cli import main
from bvhlab.library import load_scene, procedural, showcase
from bvhlab.png import linear_to_srgb


def run_cli(*args, timeout=300):
    """The CLI in a child process (it may load .blend files through bpy, which changes global state)."""
    done = subprocess.run(
        [sys.executable, "-m", "bvhlab", *map(str, args)], capture_output=True, text=True, timeout=timeout
    )
    return done.returncode, done.stdout, done.stderr


def test_help_and_scenes(capsys):
    code, out, _ = run_cli("--help")
    assert code == 0 and "compare" in out and "snapshot" in out
    assert main(["scenes"]) == 0
    listed = capsys.readouterr().out
    assert "gen:five_spheres" in listed and "atrium" in listed


def test_build_json_and_csv_equal_the_api(tmp_path, capsys):
    """One stats writer (bvhlab.stats_files) for the CLI and the add-on's Export stats: the JSON is
    {"about": ..., "stats": Bvh.stats}, the CSV metric,index,value."""
    path, table = tmp_path / "stats.json", tmp_path / "stats.csv"
    assert (
        main(
            [
                "build",
                "gen:whitted",
                "--method",
                "sah32",
                "--max-leaf-size",
                "2",
                "--json",
                str(path),
                "--csv",
                str(table),
            ]
        )
        == 0
    )
    written = json.loads(path.read_text())
    scene, _ = load_scene("gen:whitted")
    api = bvhlab.build(scene, method="sah", bins=32, max_leaf_size=2).stats
    assert set(written) == {"about", "stats"} and written["about"]["scene"] == "whitted"
    assert written["about"]["settings"] == {
        "method": "sah",
        "bins": 32,
        "axis": bvhlab.build_config.DEFAULT_AXIS,
        "bin_bounds": bvhlab.build_config.DEFAULT_BIN_BOUNDS,
        "max_leaf_size": 2,
        "sah_block": bvhlab.build_config.DEFAULT_SAH_BLOCK,
    }
    for key in api:
        if key not in ("build_ms",):
            assert written["stats"][key] == api[key], key
    rows = list(csv.DictReader(table.open()))
    assert [int(r["value"]) for r in rows if r["metric"] == "nodes_per_depth"] == api["nodes_per_depth"]
    assert float(next(r["value"] for r in rows if r["metric"] == "sah_cost")) == pytest.approx(api["sah_cost"])
    out = capsys.readouterr().out
    assert "nodes/depth" in out and "  bins          32" in out
    assert main(["build", "gen:whitted", "--method", "median"]) == 0
    out = capsys.readouterr().out  # a median tree has no bins: no line (it printed "bins None")
    assert "  method        median" in out and "bins" not in out


def line_pixels(png_path, depth: int) -> int:
    """Pixels showing the overlay colour of `depth` (as written to the sRGB PNG)."""
    image = read_png(png_path)[..., :3].astype(int)
    colour = (linear_to_srgb(bvhlab._core.depth_colors(np.array([depth], np.uint32))[0]) * 255 + 0.5).astype(int)
    return int(np.all(np.abs(image - colour) <= 1, -1).sum())


def test_render_with_overlay_and_heatmap(tmp_path, capsys):
    """Traversal auto (the default) on the CPU: the wide walk for the image (the stack walk's PNG,
    byte for byte), the stack walk where the counts are the picture (--heatmap: the stack walk's
    box tests)."""
    out = tmp_path / "render.png"
    assert (
        main(
            [
                "render",
                "gen:five_spheres",
                "--width",
                "96",
                "--height",
                "64",
                "--backend",
                "cpu",
                "--method",
                "median",
                "--bvh-depth",
                "1:1",
                "--out",
                str(out),
            ]
        )
        == 0
    )
    strip = legend.depth_legend(96, [1]).shape[0]  # the depth colours' legend under the image
    assert read_png(out).shape == (64 + strip, 96, 4)
    assert line_pixels(out, 1) > 20 and line_pixels(out, 2) == 0
    assert "wide walk" in capsys.readouterr().out
    stack_out = tmp_path / "stack.png"
    shape = ["--width", "96", "--height", "64", "--backend", "cpu", "--method", "median", "--bvh-depth", "1:1"]
    assert main(["render", "gen:five_spheres", *shape, "--traversal", "stack", "--out", str(stack_out)]) == 0
    assert stack_out.read_bytes() == out.read_bytes()
    # a range past the tree's deepest boxes: said, and no empty legend strip (it drew nothing silently)
    past = tmp_path / "past.png"
    shape[-1] = "40:45"
    assert main(["render", "gen:five_spheres", *shape, "--out", str(past)]) == 0
    assert read_png(past).shape == (64, 96, 4)
    assert "--bvh-depth 40:45 draws none" in capsys.readouterr().err
    snapshot = tmp_path / "snapshot.png"  # the raster's snapshot says it too (probe: it was silent)
    assert main(["snapshot", "gen:five_spheres", "--bvh-depth", "40:45", "--out", str(snapshot)]) == 0
    assert "--bvh-depth 40:45 draws none" in capsys.readouterr().err and snapshot.exists()
    # --width and --height of a sheet are its panels' (they were accepted and ignored)
    sheets = [tmp_path / "sheet.png", tmp_path / "small_sheet.png"]
    assert main(["snapshot", "gen:five_spheres", "--sheet", "--out", str(sheets[0])]) == 0
    size = ["--width", "100", "--height", "80"]
    assert main(["snapshot", "gen:five_spheres", "--sheet", *size, "--out", str(sheets[1])]) == 0
    (w0, h0), (w1, h1) = (struct.unpack(">II", s.read_bytes()[16:24]) for s in sheets)  # IHDR
    assert w1 * 320 == w0 * 100 and h1 < h0, (w0, h0, w1, h1)
    heat = tmp_path / "heat.png"
    assert (
        main(
            [
                "render",
                "gen:five_spheres",
                "--width",
                "32",
                "--height",
                "24",
                "--backend",
                "cpu",
                "--heatmap",
                "--out",
                str(heat),
            ]
        )
        == 0
    )
    assert read_png(heat).shape == (24 + legend.heat_bar(32, 0, 1).shape[0], 32, 4)  # --counter box_tests
    assert np.load(heat.with_suffix(".npy")).shape == (24, 32)
    assert "wide walk" not in capsys.readouterr().out
    stack_heat = tmp_path / "stack_heat.png"
    small = ["--width", "32", "--height", "24", "--backend", "cpu", "--heatmap", "--traversal", "stack"]
    assert main(["render", "gen:five_spheres", *small, "--out", str(stack_heat)]) == 0
    np.testing.assert_array_equal(np.load(heat.with_suffix(".npy")), np.load(stack_heat.with_suffix(".npy")))


def test_render_with_a_transparent_film(tmp_path):
    """--film-transparent: the PNG's alpha is the share of each pixel's camera rays that hit (the
    sky 0, the spheres' insides 255), its colour straight (PNG's convention): where every ray hits,
    the opaque render's pixel."""
    args = ["render", "gen:five_spheres", "--width", "48", "--height", "32", "--backend", "cpu"]
    args += ["--samples-per-axis", "2"]
    film, opaque = tmp_path / "film.png", tmp_path / "opaque.png"
    assert main([*args, "--film-transparent", "--out", str(film)]) == 0
    assert main([*args, "--out", str(opaque)]) == 0
    a, b = read_png(film).astype(int), read_png(opaque).astype(int)
    alpha = a[..., 3]
    assert (alpha == 0).mean() > 0.2 and (alpha == 255).mean() > 0.05 and ((alpha > 0) & (alpha < 255)).any()
    assert np.all(b[..., 3] == 255)
    full = alpha == 255
    assert np.abs(a[full][:, :3] - b[full][:, :3]).max() <= 1
    # at silhouettes, the straight colour over the sky is the opaque image's pixel (in linear light;
    # within the 8-bit rounding of both PNGs)
    edge = (alpha > 0) & (alpha < 255)
    linear = lambda c: np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)  # noqa: E731
    sky = np.array(showcase.five_spheres().sky)
    over = linear(a[edge][:, :3] / 255) * (alpha[edge] / 255)[:, None] + sky * (1 - alpha[edge] / 255)[:, None]
    assert np.abs(over - linear(b[edge][:, :3] / 255)).max() < 0.02


def test_errors_have_exit_code_2(tmp_path, capsys):
    assert main(["build", str(tmp_path / "missing.npz")]) == 2
    assert "no scene file" in capsys.readouterr().err
    assert main(["build", "gen:whitted", "--method", "quick"]) == 2
    assert "unknown method 'quick'" in capsys.readouterr().err
    assert main(["build", "no-such-scene"]) == 2
    assert "gen:whitted" in capsys.readouterr().err  # the message lists the names
    empty = tmp_path / "empty.npz"
    bvhlab.Scene(camera=bvhlab.Camera((0, -5, 1), (0, 0, 0))).save(empty)
    assert main(["compare", str(empty), "--out", str(tmp_path / "c")]) == 2
    assert "no geometry" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        main(["render", "gen:whitted", "--bvh-depth", "9:2", "--out", str(tmp_path / "x.png")])


def test_render_an_instanced_scene_without_flattening(tmp_path, capsys):
    """The CLI renders an instanced scene with its two-level tree (issue 34): the image equals the
    flattened scene's (no mirrored instance here, so flattening keeps every outside out)."""
    knot = procedural.torus_knot(2000)
    transforms = np.tile(np.eye(3, 4, dtype=np.float32), (3, 1, 1))
    transforms[:, 0, 3] = [0.0, 3.0, 6.0]
    transforms[1, :, :3] *= 0.5
    scene = bvhlab.Scene(triangles=knot, instance_mesh=[0, 0, 0], instance_transforms=transforms)
    scene.camera = bvhlab.Camera((3.0, -12.0, 4.0), (3.0, 0.0, 0.0), (0.0, 0.0, 1.0), 50.0)
    path = scene.save(tmp_path / "three.npz")
    out, flat_out = tmp_path / "three.png", tmp_path / "flat.png"
    assert main(["render", str(path), "--width", "64", "--height", "48", "--backend", "cpu", "--out", str(out)]) == 0
    assert "3 instances of 1 meshes" in capsys.readouterr().out
    flat = scene.flattened().save(tmp_path / "flat.npz")
    assert (
        main(["render", str(flat), "--width", "64", "--height", "48", "--backend", "cpu", "--out", str(flat_out)]) == 0
    )
    a, b = read_png(out).astype(int), read_png(flat_out).astype(int)
    assert (np.abs(a - b).max(-1) > 2).mean() <= 0.01
    assert (a != a[0, 0]).any(-1).mean() > 0.1  # the knots are in view


@pytest.fixture(scope="module")
def bad_scene_files(tmp_path_factory):
    d = tmp_path_factory.mktemp("cli_files")
    good = d / "good.npz"
    bvhlab.Scene(triangles=procedural.random_triangles(50, seed=1)).save(good)
    with np.load(good) as f:
        arrays = dict(f)
    np.savez(d / "no_triangles.npz", **{k: v for k, v in arrays.items() if k != "triangles"})
    np.savez(d / "materials5.npz", **{**arrays, "materials": np.zeros((1, 5))})
    (d / "truncated.npz").write_bytes(good.read_bytes()[:300])
    (d / "text.blend").write_text("not a .blend file")
    (d / "a_file").write_text("")
    (d / "a_folder").mkdir()
    return d


@pytest.mark.parametrize(
    "args, message",
    [
        (["build", "{d}/truncated.npz"], "truncated.npz is not an .npz file"),
        (["build", "{d}/no_triangles.npz"], "no_triangles.npz has no 'triangles'"),
        (["build", "{d}/materials5.npz"], "materials has 5 columns; a scene of format 4 has 8"),
        # bpy's RuntimeError, "Error: File format is not supported …" and a blank line after the CLI's
        (["build", "{d}/text.blend"], r"text\.blend cannot be read as a \.blend file: File format is not supported"),
        (["build", "{d}/good.npz", "--json", "{d}/a_file/stats.json"], "a_file is a file, not a folder"),
        (["build", "{d}/good.npz", "--json", "{d}/a_folder"], "a_folder is a folder"),
        (["build", "{d}/good.npz", "--csv", "{d}/stats.json"], "written as .csv"),
        (["render", "{d}/good.npz", "--out", "{d}/r.jpg"], r"r.jpg: a PNG image is written as .png"),
        (["render", "{d}/good.npz", "--out", "{d}/a_folder"], "a_folder is a folder"),
        (["render", "{d}/good.npz", "--out", "{d}/a_file/r.png"], "a_file is a file, not a folder"),
        (["render", "{d}/good.npz", "--bvh-depth", "-1:2", "--out", "{d}/r.png"], "depth range -1:2: need 0 <= A <= B"),
        (["snapshot", "{d}/good.npz", "--bvh-depth", "300:301", "--out", "{d}/s.png"], "depths go up to 255"),
        (["inspect", "{d}/good.npz", "--pixel", "-1,5"], "pixel -1,5: coordinates must be >= 0"),
        (["inspect", "{d}/good.npz", "--pixel", "3,-2"], "pixel 3,-2: coordinates must be >= 0"),
        (
            ["render", "{d}/good.npz", "--counter", "box_tests", "--range", "-1.5e0,-5", "--out", "{d}/r.png"],
            "range must be two finite numbers LO < HI, got -1.5, -5.0",
        ),
        (["animate", "wave", "--frames", "-1-2", "--out", "{d}/a"], "frames must look like A-B"),
        # int() took them: 10-12, and another script's digits
        (["animate", "wave", "--frames", "1_0-12", "--out", "{d}/a"], "frames must look like A-B"),
        (["animate", "wave", "--frames", "\u0661-\u0663", "--out", "{d}/a"], "frames must look like A-B"),
        (
            ["render", "{d}/good.npz", "--max-depth", "20", "--out", "{d}/r.png"],
            "argument --max-depth: must be between 0 and 15, got 20",
        ),  # was "max_depth must be ..."
        (
            ["render", "{d}/good.npz", "--width", "100000", "--out", "{d}/r.png"],
            "between 1 and 16384 pixels, got 100000",
        ),
        (["snapshot", "{d}/good.npz", "--width", "0", "--out", "{d}/s.png"], "between 1 and 16384 pixels, got 0"),
        (["snapshot", "{d}/good.npz", "--height", "100000", "--out", "{d}/s.png"], "between 1 and 16384 pixels"),
        # it ran a local cluster instead
        (["sweep", "{d}/spec.toml", "--scheduler", " ", "--out", "{d}/w"], "the scheduler's address is empty"),
        # the messages named int64's bounds, the API's name, numpy's overflow warning before the image
        (["build", "{d}/good.npz", "--method", "sah99999999999999999999"], "bins must be between 2 and 256, got"),
        # sah32's bins were dropped for --bins' (an audit): refused as a sweep spec refuses them
        (["build", "{d}/good.npz", "--method", "sah32", "--bins", "8"], "'sah32' gives the bins; give bins or sah<B>"),
        (["build", "{d}/good.npz", "--method", "sah²"], "unknown method 'sah²'"),
        (["build", "{d}/good.npz", "--optimize", "2", "--optimize-ms", "1e308"], "--optimize-ms must be within"),
        (
            ["render", "{d}/good.npz", "--counter", "box_tests", "--range", "1e40,1e41", "--out", "{d}/r.png"],
            "range must be two numbers LO < HI that float32 tells apart",
        ),
    ],
)
def test_bad_files_and_paths_are_one_error_line(bad_scene_files, args, message):
    """Issue 8: BadZipFile, KeyError and IndexError tracebacks, --json under a file or on a folder,
    PNG bytes written to r.jpg, argparse's "expected one argument", moderngl errors: now
    `bvhlab CMD: error: ...`, exit 2, nothing written, no traceback."""
    import re

    before = sorted(p.name for p in bad_scene_files.iterdir())
    code, out, err = run_cli(*[a.format(d=bad_scene_files) for a in args], timeout=120)
    assert code == 2, (code, out, err)
    assert "Traceback" not in err
    last = err.strip().splitlines()[-1]
    assert last.startswith(f"bvhlab {args[0]}: error: ") and re.search(message, last), err
    assert sorted(p.name for p in bad_scene_files.iterdir()) == before


def test_files_that_go_together_are_kept_together_when_interrupted(tmp_path, monkeypatch, capsys):
    # one file at a time, an interrupt left a new counter image beside its old histogram, and a new
    # stats JSON beside its old CSV (probe); now all of them are written at once or none
    from bvhlab import stats_files
    from bvhlab.cli import render_cmd

    out = tmp_path / "c.png"
    render = ["render", "gen:five_spheres", "--counter", "box_tests", "--width", "24", "--height", "16"]
    assert main([*render, "--backend", "cpu", "--out", str(out)]) == 0
    before = {p.name: p.read_bytes() for p in tmp_path.iterdir()}
    assert len(before) == 4, sorted(before)  # the image, its counts, the histogram strip and numbers

    def interrupted(*_args, **_kwargs):
        raise KeyboardInterrupt

    real = render_cmd.histogram.histogram_strip
    monkeypatch.setattr(render_cmd.histogram, "histogram_strip", interrupted)  # after the image's bytes
    assert main([*render, "--width", "32", "--backend", "cpu", "--out", str(out)]) == 130
    assert {p.name: p.read_bytes() for p in tmp_path.iterdir()} == before
    monkeypatch.setattr(render_cmd.histogram, "histogram_strip", real)

    stats = tmp_path / "stats"
    build = ["build", "gen:five_spheres", "--json", str(stats / "s.json"), "--csv", str(stats / "s.csv")]
    assert main(build) == 0
    kept = {p.name: p.read_bytes() for p in stats.iterdir()}
    monkeypatch.setattr(stats_files, "stats_csv", interrupted)  # after the JSON's text
    assert main([*build, "--method", "median"]) == 130
    assert {p.name: p.read_bytes() for p in stats.iterdir()} == kept
    capsys.readouterr()
