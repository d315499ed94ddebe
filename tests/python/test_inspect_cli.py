"""`bvhlab inspect` end to end: what it prints and writes equals the Python API's figures for the
same tree, a pixel's table equals the CPU tracer's cost there, saved trees are read back, and bad
requests end with one clear line and exit code 2."""

import json

import numpy as np
import pytest

import bvhlab
from bvhlab.cli import main
from bvhlab.inspect.ray_record import trace_pixel
from bvhlab.library import load_scene


@pytest.fixture(scope="module")
def whitted():
    scene, _ = load_scene("gen:whitted")
    return scene, bvhlab.build(scene, method="sah", bins=32, max_leaf_size=2)


def _run(tmp_path, *args):
    path = tmp_path / "out.json"
    assert (
        main(["inspect", "gen:whitted", "--method", "sah32", "--max-leaf-size", "2", *args, "--json", str(path)]) == 0
    )
    return json.loads(path.read_text())


def test_node(tmp_path, whitted, capsys):
    _, bvh = whitted
    report = _run(tmp_path, "--node", "5")
    data = bvh.node_data()
    assert report["node"] == data.node(5)
    assert report["tree"]["sah_cost"] == pytest.approx(bvh.stats["sah_cost"])
    assert report["tree"]["epo_cost"] == pytest.approx(data.epo_cost) and data.epo_cost > 0
    out = capsys.readouterr().out
    assert "node 5 (" in out and "sah_share" in out and "epo_cost" in out


def test_worst(tmp_path, whitted):
    _, bvh = whitted
    rows = _run(tmp_path, "--worst", "7")["worst"]
    data = bvh.node_data()
    assert [r["node"] for r in rows] == list(data.worst(7))
    costs = [r["subtree_sah"] for r in rows]
    assert costs == sorted(costs, reverse=True) and rows[0]["node"] == 0
    # no node left out costs more than the last one shown
    shown = {r["node"] for r in rows}
    assert max(c for i, c in enumerate(data.subtree_sah) if i not in shown) <= costs[-1]


@pytest.mark.parametrize("traversal", ["stack", "stackless"])
def test_pixel_equals_the_tracers_cost(tmp_path, whitted, capsys, traversal):
    scene, bvh = whitted
    w, h, x, y = 64, 48, 30, 26
    report = _run(tmp_path, "--pixel", f"{x},{y}", "--width", str(w), "--height", str(h), "--traversal", traversal)
    pixel = report["pixel"]
    job = bvhlab.Renderer("cpu").start(scene, bvh, w, h, options=bvhlab.RenderOptions(traversal=traversal))
    job.run()
    assert pixel["box_tests"] == job.result(color=False, depth=False).cost[y, x]
    steps = pixel["steps"]
    assert sum(s["step"] == "box" for s in steps) == pixel["box_tests"]
    assert sum(s["step"] == "prim" for s in steps) == pixel["prim_tests"]
    closer = [s for s in steps if s["step"] == "prim" and s["closer"]]
    assert pixel["hit_leaf"] >= 0 and closer[-1]["leaf"] == pixel["hit_leaf"]
    rec = trace_pixel(scene, bvh, x, y, width=w, height=h, options=bvhlab.RenderOptions(traversal=traversal))
    assert (pixel["prim"], pixel["t"]) == (rec.prim, rec.t)
    table = capsys.readouterr().out
    assert f"box_tests {pixel['box_tests']}," in table and "closest so far" in table


def test_saved_tree_is_read_back(tmp_path, whitted):
    tree = tmp_path / "w.bvhtree"
    first = _run(tmp_path, "--node", "3", "--save-tree", str(tree))
    assert tree.exists()
    again = main(["inspect", "gen:whitted", "--tree", str(tree), "--node", "3", "--json", str(tmp_path / "b.json")])
    assert again == 0
    second = json.loads((tmp_path / "b.json").read_text())
    assert second["node"] == first["node"] and second["tree"] == first["tree"]


def test_bad_requests(tmp_path, capsys):
    tree = tmp_path / "w.bvhtree"
    assert main(["inspect", "gen:whitted", "--node", "0", "--save-tree", str(tree)]) == 0
    capsys.readouterr()
    assert main(["inspect", "gen:five_spheres", "--tree", str(tree), "--node", "0"]) == 2
    assert "saved for other geometry" in capsys.readouterr().err
    assert main(["inspect", "gen:whitted", "--node", "100000"]) == 2
    assert "does not exist" in capsys.readouterr().err
    assert main(["inspect", "gen:whitted", "--pixel", "900,10"]) == 2
    assert "outside the 800×600 image" in capsys.readouterr().err
    for bad in (["--pixel", "3"], ["--node", "1", "--worst", "2"], []):
        with pytest.raises(SystemExit) as e:
            main(["inspect", "gen:whitted", *bad])
        assert e.value.code == 2
    err = capsys.readouterr().err
    assert "X,Y" in err and "not allowed with" in err and "one of the arguments" in err
    np.testing.assert_equal(sorted(p.name for p in tmp_path.iterdir()), ["w.bvhtree"])


@pytest.mark.parametrize(
    "args",
    [
        ["--worst", "1", "--sample", "3"],
        ["--node", "0", "--width", "3"],
        ["--node", "0", "--traversal", "stackless"],
        ["--worst", "2", "--samples-per-axis", "4"],
        ["--node", "0", "--height", "600"],
    ],
)
def test_pixel_options_need_pixel(args, capsys):
    """The probe's cases: the options of --pixel were accepted with --node and --worst, and ignored."""
    assert main(["inspect", "gen:whitted", *args]) == 2
    option = args[2]
    assert f"{option} is an option of --pixel X,Y" in capsys.readouterr().err


def test_a_missed_pixel_is_strict_json(tmp_path):
    """A pixel whose ray hits nothing: its distance is null (it was Infinity, which strict JSON
    parsers refuse)."""
    path = tmp_path / "px.json"
    assert (
        main(["inspect", "gen:whitted", "--pixel", "0,0", "--width", "16", "--height", "12", "--json", str(path)]) == 0
    )

    def refuse(token):
        raise ValueError(f"not JSON: {token}")

    report = json.loads(path.read_text(), parse_constant=refuse)
    assert report["pixel"]["t"] is None and report["pixel"]["prim"] < 0


def test_build_options_beside_a_saved_tree_must_be_its_own(tmp_path, capsys):
    """--tree with --method median on a tree saved as sah32: refused (the options were ignored and the
    saved tree inspected as if it were the one asked for); the tree's own options, or none, read it."""
    tree = tmp_path / "w.bvhtree"
    assert main(["inspect", "gen:whitted", "--method", "sah32", "--node", "0", "--save-tree", str(tree)]) == 0
    capsys.readouterr()
    assert main(["inspect", "gen:whitted", "--tree", str(tree), "--method", "median", "--node", "0"]) == 2
    assert "was built with method" in capsys.readouterr().err
    assert main(["inspect", "gen:whitted", "--tree", str(tree), "--method", "sah32", "--node", "0"]) == 0
    assert main(["inspect", "gen:whitted", "--tree", str(tree), "--node", "0"]) == 0
    # an option typed that is the default is compared too; one typed alone is compared alone
    # (a review: --method sah passed on an SBVH tree, --max-leaf-size 8 was refused on its own tree)
    sbvh = tmp_path / "s.bvhtree"
    assert main(["inspect", "gen:whitted", "--method", "sbvh", "--max-leaf-size", "8", "--node", "0",
                 "--save-tree", str(sbvh)]) == 0  # fmt: skip
    capsys.readouterr()
    assert main(["inspect", "gen:whitted", "--tree", str(sbvh), "--method", "sah", "--node", "0"]) == 2
    assert "was built with method=sbvh, not method=sah" in capsys.readouterr().err
    assert main(["inspect", "gen:whitted", "--tree", str(sbvh), "--max-leaf-size", "8", "--node", "0"]) == 0


def test_optimize_ms_needs_optimize(capsys):
    assert main(["build", "gen:whitted", "--optimize-ms", "5"]) == 2
    assert "--optimize N" in capsys.readouterr().err


def test_a_node_out_of_range_is_refused_before_the_node_figures(tmp_path, monkeypatch, capsys):
    """--node past the tree: refused from the tree's node count, before node_data's EPO pass (it
    came after it: 39 s of a 15,000-triangle soup); --worst over a one-node tree says one subtree
    ("the 5 subtrees" over one row)."""

    def no_epo(self):
        raise AssertionError("node_data ran")

    monkeypatch.setattr(bvhlab.Bvh, "node_data", no_epo)
    assert main(["inspect", "gen:whitted", "--node", "100000"]) == 2
    assert "--node 100000 does not exist: the tree has" in capsys.readouterr().err
    monkeypatch.undo()
    one = tmp_path / "one.npz"
    bvhlab.Scene(triangles=np.array([[[0, 0, 0], [1, 0, 0], [0, 1, 0]]], np.float32)).save(one)
    assert main(["inspect", str(one), "--worst", "5"]) == 0
    assert "the one subtree of largest SAH cost" in capsys.readouterr().out


def test_inspect_writes_into_folders_it_makes_as_build_does(tmp_path):
    """--json and --save-tree into a folder that did not exist were refused after the build and the
    analysis ("No such file or directory"); build --json makes the folder (probe)."""
    report, tree = tmp_path / "a" / "b" / "s.json", tmp_path / "c" / "t.bvhtree"
    assert main(["inspect", "gen:five_spheres", "--worst", "2", "--json", str(report), "--save-tree", str(tree)]) == 0
    assert json.loads(report.read_text()) and tree.stat().st_size > 0


def test_the_tree_and_the_report_are_written_together(tmp_path, monkeypatch):
    """--save-tree was written before the report was made: a Ctrl-C during the report (its EPO pass
    takes seconds on large trees) or a report that could not be written left the old tree replaced
    and no report (helper probe, 2026-12-07). Now both are written together, or neither."""
    from bvhlab.cli import inspect_cmd

    tree, report = tmp_path / "t.bvhtree", tmp_path / "r.json"
    assert main(["inspect", "gen:five_spheres", "--method", "median", "--node", "0", "--save-tree", str(tree)]) == 0
    before = tree.read_bytes()
    real = inspect_cmd._report

    def interrupted(*args, **kwargs):
        real(*args, **kwargs)
        raise KeyboardInterrupt

    monkeypatch.setattr(inspect_cmd, "_report", interrupted)
    with pytest.raises(KeyboardInterrupt):
        inspect_cmd.run(
            inspect_cmd_args(["gen:five_spheres", "--node", "0", "--save-tree", str(tree), "--json", str(report)])
        )
    assert tree.read_bytes() == before and not report.exists()
    assert [p.name for p in tmp_path.iterdir()] == ["t.bvhtree"]  # no temporary left
    monkeypatch.undo()
    assert main(["inspect", "gen:five_spheres", "--node", "0", "--save-tree", str(tree), "--json", str(report)]) == 0
    assert tree.read_bytes() != before and json.loads(report.read_text())["tree"]
    scene, _ = load_scene("gen:five_spheres")
    assert bvhlab.load_bvh(tree, scene).config.method == "sah"


@pytest.mark.parametrize(
    "argv, message",
    [
        (["gen:five_spheres", "--pixel", "1,1", "--sample", "1"], "sample 1 does not exist: a pixel has one sample"),
        (["gen:five_spheres", "--node", "0", "--tree", "{d}/missing.bvhtree"], "missing.bvhtree: No such file"),
        (["gen:five_spheres", "--node", "0", "--tree", "{d}"], "is a folder, not a tree file"),
        (["gen:knot_field", "--node", "0", "--save-tree", "{d}/t.bvhtree"], "--save-tree takes a flat scene's tree"),
        (["gen:knot_field", "--node", "0", "--optimize", "3"], "--optimize takes a flat scene's tree"),
    ],
)
def test_requests_the_scene_or_tree_cannot_answer_are_refused_before_the_build(
    tmp_path, capsys, monkeypatch, argv, message
):
    """Each was refused after the scene was loaded and its tree built (helper probe, 2026-12-07)."""
    from bvhlab.cli import inspect_cmd

    built = []
    monkeypatch.setattr(inspect_cmd, "build", lambda *a, **k: built.append(1))
    assert main(["inspect", *(a.replace("{d}", str(tmp_path)) for a in argv)]) == 2
    assert message in capsys.readouterr().err and not built


def inspect_cmd_args(argv: list[str]):
    """`bvhlab inspect ARGV`'s parsed arguments, as main gives them to inspect_cmd.run."""
    from bvhlab.cli import parser

    return parser().parse_args(["inspect", *argv])


@pytest.mark.parametrize("request_", [["--node", "99999"], ["--pixel", "5000,5000"]])
def test_a_request_the_tree_cannot_answer_saves_nothing(tmp_path, capsys, request_):
    # the tree was built and saved, then the node or pixel refused (exit 2 beside a new file)
    tree = tmp_path / "t.bvhtree"
    assert main(["inspect", "gen:whitted", *request_, "--save-tree", str(tree)]) == 2
    assert not tree.exists()
    err = capsys.readouterr().err
    assert "does not exist" in err or "outside the 800×600 image" in err, err


def test_a_reader_gone_keeps_the_files_and_ends_quietly(tmp_path):
    # `bvhlab inspect ... --json F | head -1`: the report was printed before F was written, and the
    # broken pipe ended the command ("error: [Errno 32] Broken pipe", 2) without F
    import os
    import subprocess
    import sys

    report, stats = tmp_path / "w.json", tmp_path / "b.json"
    # a pipe's output is buffered (unless PYTHONUNBUFFERED is set, as on some machines): both ways
    buffered = {k: v for k, v in os.environ.items() if k != "PYTHONUNBUFFERED"}
    runs = [
        (["inspect", "gen:whitted", "--worst", "50", "--json", str(report)], buffered),
        (["inspect", "gen:whitted", "--worst", "50", "--json", str(report)], {**buffered, "PYTHONUNBUFFERED": "1"}),
        (["build", "gen:whitted", "--json", str(stats)], {**buffered, "PYTHONUNBUFFERED": "1"}),
        (["scenes"], buffered),
        (["scenes"], {**buffered, "PYTHONUNBUFFERED": "1"}),
    ]
    for args, env in runs:
        child = subprocess.Popen(
            [sys.executable, "-m", "bvhlab", *args], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env
        )
        assert child.stdout is not None and child.stderr is not None
        child.stdout.close()  # the reader gone before the first line
        err = child.stderr.read()
        assert child.wait(timeout=300) == 141 and "Broken pipe" not in err and "Traceback" not in err, err
    assert json.loads(report.read_text())["worst"] and json.loads(stats.read_text())["stats"]
