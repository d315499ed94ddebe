"""Runs the UI scenarios (tests/blender/ui/scenario_*.py) in a real Blender window under Xvfb and
checks the pictures. Runs inside the Debian 13 root (make blender-ui-test):

    python tests/blender/ui/run_ui.py --zip dist/bvhlab.zip [--out build/ui] [--screenshots docs]
                                      [--only panel ...] [--blender blender]

Per scenario: a fresh user folder, Blender with a 1600×900 window on the scenario's bundled scene,
the scenario's steps run by tests/blender/ui/session.py; this driver answers its requests (screen
captures with xwd, key presses and Ctrl+wheel with xdotool), saves every capture as PNG in --out,
and runs the scenario's `check(shots, info)`. Exit code 1 when any scenario fails.

A new scenario is one more file scenario_NAME.py with SCENE, SCREENSHOTS, steps(session) and
check(shots, info), and optionally screenshot_text(info) (text chunks for its pictures) (see
scenario_panel.py); this driver finds it by its name.
"""

from __future__ import annotations

import argparse
import importlib
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[2]
sys.path.insert(0, str(HERE))
import xshot  # noqa: E402

DISPLAY = ""  # the X display start_x got: ":N"
SIZE = (1600, 900)


def start_x() -> subprocess.Popen:
    """Xvfb on a free display number (-displayfd: it picks one and says which): another UI run in
    the same root (its /tmp/.X11-unix is shared) keeps its own screen."""
    global DISPLAY
    read_end, write_end = os.pipe()
    server = subprocess.Popen(
        ["Xvfb", "-displayfd", str(write_end), "-screen", "0", f"{SIZE[0]}x{SIZE[1]}x24", "-nolisten", "tcp"],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        pass_fds=(write_end,),
    )
    os.close(write_end)
    with os.fdopen(read_end) as said:
        number = said.readline().strip()
    if not number.isdigit():
        server.kill()
        raise SystemExit("Xvfb did not start")
    DISPLAY = f":{number}"
    return server


def answer(request: dict, shots_dir: Path, shots: dict) -> None:
    """Carry out one request of the scenario."""
    env = dict(os.environ, DISPLAY=DISPLAY)
    if request["action"] == "capture":
        shots[request["name"]] = image = xshot.capture(DISPLAY)
        xshot.write_png(shots_dir / f"{request['name']}.png", image)
    elif request["action"] == "key":
        subprocess.run(
            ["xdotool", "mousemove", str(request["x"]), str(request["y"]), "key", request["key"]], env=env, check=True
        )
    elif request["action"] == "click":
        subprocess.run(
            ["xdotool", "mousemove", str(request["x"]), str(request["y"]), "click", str(request.get("button", 1))],
            env=env,
            check=True,
        )
    elif request["action"] == "scroll":
        keys = (["keydown", "ctrl"], ["keyup", "ctrl"]) if request.get("ctrl") else ([], [])
        subprocess.run(
            ["xdotool", "mousemove", str(request["x"]), str(request["y"]), *keys[0], "click", "5", *keys[1]],
            env=env,
            check=True,
        )
    else:
        raise ValueError(f"unknown request {request}")
    (shots_dir / f"done-{request['id']:03d}").touch()


def run_scenario(name: str, args) -> tuple[list[str], dict, dict]:
    """(failures, shots, info) of one scenario."""
    scenario = importlib.import_module(f"scenario_{name}")
    shots_dir = (args.out / name).resolve()
    shutil.rmtree(shots_dir, ignore_errors=True)
    shots_dir.mkdir(parents=True)
    user = tempfile.mkdtemp(prefix="bvhlab_ui_user_")
    scene = ROOT / "blender_scenes" / f"{scenario.SCENE}.blend"
    command = [
        args.blender,
        "--factory-startup",
        "-p",
        "0",
        "0",
        str(SIZE[0]),
        str(SIZE[1]),
        str(scene),
        "--python",
        str(HERE / f"scenario_{name}.py"),
        "--",
        "--zip",
        str(args.zip.resolve()),
        "--shots",
        str(shots_dir),
    ]
    env = dict(os.environ, DISPLAY=DISPLAY, BLENDER_USER_RESOURCES=user)
    shots: dict = {}
    with (shots_dir / "blender.log").open("w") as log:
        blender = subprocess.Popen(command, env=env, stdout=log, stderr=subprocess.STDOUT)
        deadline = time.time() + args.timeout
        while blender.poll() is None and time.time() < deadline:
            for request in sorted(shots_dir.glob("request-*.json")):
                if not (shots_dir / f"done-{request.stem[8:]}").exists():
                    answer(json.loads(request.read_text()), shots_dir, shots)
            time.sleep(0.05)
        if blender.poll() is None:
            blender.kill()
            return [f"Blender did not finish within {args.timeout} s"], shots, {}
    shutil.rmtree(user, ignore_errors=True)
    result_path = shots_dir / "result.json"
    if not result_path.exists():
        return [f"Blender exited ({blender.returncode}) without a result; see {shots_dir / 'blender.log'}"], shots, {}
    result = json.loads(result_path.read_text())
    if result["error"]:
        return [f"the scenario raised:\n{result['error']}"], shots, result["info"]
    failures = scenario.check(shots, result["info"])
    if blender.returncode != 0:
        failures.append(f"Blender exited with {blender.returncode}")
    return failures, shots, result["info"]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--zip", type=Path, required=True)
    ap.add_argument("--out", type=Path, default=ROOT / "build" / "ui")
    ap.add_argument("--screenshots", type=Path, default=None, help="copy the scenarios' SCREENSHOTS here")
    ap.add_argument("--only", nargs="+", default=None)
    ap.add_argument("--blender", default="blender")
    ap.add_argument("--timeout", type=float, default=240)
    args = ap.parse_args(argv)
    names = args.only or sorted(p.stem[len("scenario_") :] for p in HERE.glob("scenario_*.py"))
    server = start_x()
    failed = 0
    try:
        for name in names:
            started = time.time()
            failures, shots, info = run_scenario(name, args)
            summary = {k: v for k, v in info.items() if k not in ("layouts", "palette")}
            print(f"{name}: {json.dumps(summary, default=str)}")
            for failure in failures:
                print(f"  {failure}")
            print(
                f"{'FAIL' if failures else 'PASS'} ui: {name} ({time.time() - started:.0f} s; pictures in "
                f"{args.out / name})",
                flush=True,
            )
            failed += bool(failures)
            if args.screenshots is not None and not failures:
                scenario = importlib.import_module(f"scenario_{name}")
                for shot, file_name in scenario.SCREENSHOTS.items():
                    area = info.get("area")
                    image = (
                        shots[shot]
                        if area is None
                        else shots[shot][area["y"] : area["y"] + area["height"], area["x"] : area["x"] + area["width"]]
                    )
                    text = scenario.screenshot_text(info) if hasattr(scenario, "screenshot_text") else None
                    xshot.write_png(args.screenshots / file_name, image, text)
                    print(f"wrote {args.screenshots / file_name}")
    finally:
        server.terminate()
        server.wait()
    print(f"{len(names) - failed} passed, {failed} failed")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
