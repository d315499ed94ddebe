"""`bvhlab animate` (issue 34's experiment): per frame and policy one row; rebuilding gives a fresh
build's SAH cost every frame; every update leaves a tree whose hits equal a fresh build's; the CSV,
JSON and plot say the same; bad arguments stop before any work."""

import csv
import json

import numpy as np
import pytest

import bvhlab
from bvhlab.animate import TWO_LEVEL, run_experiment, summary
from bvhlab.cli import main
from bvhlab.library import procedural
from bvhlab.library.animations import ANIMATIONS, crowd, wave


def test_each_frame_and_policy_is_a_row_and_rebuild_is_a_fresh_build(tmp_path):
    assert main(["animate", "wave", "--size", "40", "--frames", "2-6", "--backend", "cpu",
                 "--width", "32", "--height", "24", "--out", str(tmp_path)]) == 0  # fmt: skip
    rows = list(csv.DictReader(open(tmp_path / "animate.csv")))
    policies = list(bvhlab.UPDATE_POLICIES)
    assert [(int(r["frame"]), r["policy"]) for r in rows] == [(k, p) for k in range(2, 7) for p in policies]
    for r in rows:
        assert float(r["trace_ms"]) > 0 and float(r["update_ms"]) >= 0
        if r["policy"] == "rebuild" or r["ran"] == "build":  # the same tree, summed alike: exactly
            assert float(r["sah_cost"]) == float(r["fresh_sah_cost"]) and float(r["sah_ratio"]) == 1.0
        elif r["ran"] == "refit":
            assert float(r["sah_cost"]) >= 0.999 * float(r["fresh_sah_cost"]), "a refit is no better than a build"
    report = json.loads((tmp_path / "animate.json").read_text())
    assert len(report["rows"]) == len(rows) and report["about"]["frames"] == [2, 6]
    assert report["summary"]["rebuild"]["share_of_rebuild"] == 1.0
    assert (tmp_path / "animate.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


@pytest.mark.parametrize("name", list(ANIMATIONS))
def test_every_policy_leaves_a_tree_with_a_fresh_builds_hits(name):
    frame = wave(24) if name == "wave" else crowd(12, 120)
    trees = {}

    def triangles(k):
        return frame(k / 3)

    rows = run_experiment(triangles, range(4))
    assert {r.policy for r in rows} == set(bvhlab.UPDATE_POLICIES)
    last = triangles(3)
    fresh = bvhlab.build(bvhlab.Scene(triangles=last), threads=1)
    origins, directions = procedural.random_rays(last, 2000, seed=5)
    expected = fresh.intersect(origins, directions)
    for policy in bvhlab.UPDATE_POLICIES:  # the experiment's trees are its own: update copies the same way
        trees[policy] = bvhlab.build(bvhlab.Scene(triangles=triangles(0)), threads=1)
        for k in (1, 2, 3):
            trees[policy].update(triangles(k), policy=policy)
        got = trees[policy].intersect(origins, directions)
        np.testing.assert_array_equal(np.isinf(got["t"]), np.isinf(expected["t"]))
        hit = np.isfinite(expected["t"])
        np.testing.assert_allclose(got["t"][hit], expected["t"][hit], rtol=1e-5)
    totals = summary(rows)
    assert set(totals) == set(bvhlab.UPDATE_POLICIES) and totals["refit"]["worst_sah_ratio"] >= 1.0 - 1e-6


@pytest.mark.parametrize(
    "args, message",
    [
        (["--frames", "5-2"], "need 0 <= A < B"),
        (["--frames", "x"], "must look like A-B"),
        (["--policy", "refit,shuffle"], "policies are among"),
        (["--frames", "0-20000"], "at most 10000 frames"),
    ],
)
def test_bad_arguments_stop_before_any_work(tmp_path, capsys, args, message):
    with pytest.raises(SystemExit) as exit_:
        main(["animate", "wave", "--out", str(tmp_path / "out"), *args])
    assert exit_.value.code == 2 and message in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


def test_a_folder_where_an_output_goes_is_refused_before_the_experiment(tmp_path, capsys, monkeypatch):
    """A folder named animate.png in --out was found only when the files were written, after the
    whole experiment (helper probe, 2026-12-07)."""
    from bvhlab.cli import animate_cmd

    (tmp_path / "out" / "animate.png").mkdir(parents=True)
    ran = []
    monkeypatch.setattr(animate_cmd, "run_experiment", lambda *a, **k: ran.append(1))
    assert main(["animate", "wave", "--frames", "0-3", "--out", str(tmp_path / "out")]) == 2
    assert "animate.png is a folder: the run writes its plot there" in capsys.readouterr().err
    assert not ran and sorted(p.name for p in (tmp_path / "out").iterdir()) == ["animate.png"]


def test_the_animations_keep_their_triangle_counts():
    for make, _ in ANIMATIONS.values():
        frame = make()
        assert len(frame(0.0)) == len(frame(0.7)) and len(frame(0.0)) >= 150_000


def _rising_sphere(k):
    """A static floor and a sphere rising through frames 0-3 (what moving_ball.blend animates)."""
    floor = procedural.random_triangles(200, size=0.3, seed=2)
    floor[..., 2] = 0
    return bvhlab.Scene(triangles=floor, spheres=np.array([[0.5, 0.5, 0.2 + 0.6 * k, 0.15]], np.float32))


def test_analytic_spheres_move_in_the_experiment():
    """The experiment read triangles alone: a rising sphere left every row at a SAH ratio of 1 and
    the two-level tree hitting the sphere where it started (a probe: t 98 against a fresh build's
    68). The flat rows see it move (a fresh build's SAH changes), and the two-level tree follows."""
    rows = run_experiment(_rising_sphere, range(4), ("rebuild", "refit"))
    fresh = {r.frame: r.fresh_sah_cost for r in rows if r.policy == "rebuild"}
    assert len(set(fresh.values())) == 4, fresh  # every frame's geometry differs
    refit = [r for r in rows if r.policy == "refit" and r.frame == 3][0]
    assert refit.sah_cost > refit.fresh_sah_cost  # the sphere moved away from where the tree was built
    from bvhlab.animate import _TwoLevel

    def instanced(k):
        s = _rising_sphere(k)
        return bvhlab.Scene(
            triangles=s.triangles,
            spheres=s.spheres,
            meshes=[procedural.torus_knot(200)],
            instance_mesh=np.array([0, 1]),
            instance_transforms=np.array([np.eye(4)[:3], np.eye(4)[:3] + [[0, 0, 0, 3]] * 3], np.float32),
        )

    two_level = _TwoLevel(instanced(0))
    assert two_level.update(1, instanced(3)).ran == "tlas+1 meshes"
    origins = np.array([[0.5, 0.5, 10.0]], np.float32)
    down = np.array([[0, 0, -1]], np.float32)
    expected = bvhlab.build(instanced(3)).intersect(origins, down)["t"]
    np.testing.assert_array_equal(two_level.tree.intersect(origins, down)["t"], expected)


def _strict(text: str):
    """json.loads refusing NaN and Infinity, which strict JSON parsers refuse."""

    def refuse(token):
        raise ValueError(f"not JSON: {token}")

    return json.loads(text, parse_constant=refuse)


def test_animate_json_is_strict_json_without_a_backend(tmp_path):
    """No backend: no trace time (it was written as NaN, 16 tokens a strict parser refuses); null."""
    assert main(["animate", "crowd", "--size", "2", "--frames", "0-3", "--out", str(tmp_path)]) == 0
    report = _strict((tmp_path / "animate.json").read_text())
    assert report["rows"] and all(r["trace_ms"] is None for r in report["rows"])


@pytest.mark.parametrize("name", list(ANIMATIONS))
def test_a_generated_frame_is_the_same_in_any_range(tmp_path, name):
    """The generated animations spread their whole motion over the frames asked for: frame 12 of
    `--frames 12-23` was frame 0's geometry, `0-1` and `22-23` gave the same rows, and a shorter
    range moved more a frame (worse SAH ratios for the same policy). Frame k is now one geometry
    whatever the range, as a .blend's frames are."""
    size = "20" if name == "wave" else "2"

    def fresh(frames: str) -> dict[int, float]:
        out = tmp_path / frames
        assert main(["animate", name, "--size", size, "--frames", frames, "--out", str(out)]) == 0
        rows = csv.DictReader(open(out / "animate.csv"))
        return {int(r["frame"]): float(r["fresh_sah_cost"]) for r in rows if r["policy"] == "rebuild"}

    whole, late = fresh("0-13"), fresh("12-13")
    assert late == {12: whole[12], 13: whole[13]}
    assert whole[0] != whole[12]  # the frames differ: the comparison means something


def test_adaptive_rows_say_where_the_top_was_rebuilt():
    """Adaptive's rows said "partial" whether or not it also rebuilt the levels above the subtrees
    (probe); each row now carries UpdateStats.top_boxes, here against a replay of the same frames."""
    frame = wave(30)
    rows = [r for r in run_experiment(lambda k: frame(k / 9), range(10), ["adaptive"]) if r.ran != "build"]
    tree = bvhlab.build(bvhlab.Scene(triangles=frame(0)), threads=1)
    replay = [tree.update(frame(k / 9), policy="adaptive").top_boxes for k in range(1, 10)]
    assert [r.top_boxes for r in rows] == replay
    assert any(replay), "no frame rebuilt the top: the case is not met"


def test_an_instanced_animation_where_one_mesh_gains_what_another_loses():
    """The frame's total count the same, so the frame was taken; mesh k's tree was then updated in
    place with another count, refused with an error naming neither frame nor mesh (a helper's
    audit): such a mesh's tree is built anew."""
    rng = np.random.default_rng(0)
    meshes = [rng.uniform(-1, 1, (n, 3, 3)).astype(np.float32) for n in (50, 60, 51, 59, 20)]
    eye = np.eye(3, 4, dtype=np.float32)
    transforms = np.stack(
        [eye, eye + np.float32([[0, 0, 0, 3], [0] * 4, [0] * 4]), eye + np.float32([[0] * 4, [0, 0, 0, 3], [0] * 4])]
    )

    def frame(k):
        a, b = meshes[:2] if k == 0 else meshes[2:4]
        return bvhlab.Scene(
            triangles=meshes[4], meshes=[a, b], instance_mesh=np.array([0, 1, 2]), instance_transforms=transforms
        )

    rows = run_experiment(frame, range(0, 2))
    two_level = [r for r in rows if r.policy == TWO_LEVEL]
    assert [r.frame for r in two_level] == [0, 1] and two_level[1].ran == "tlas+2 meshes"
