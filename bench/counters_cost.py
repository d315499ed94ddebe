"""What the traversal counters (issue 35) cost the CPU reference tracer: trace ms of a flat scene
with the counters kept (traversal_counters=True) and not, and, with --base, of the tracer before
the counters (a bvhlab built from the commit before them), in interleaved rounds.

    python bench/counters_cost.py [--scene atrium] [--width 320 --height 240] [--rounds 5]
        [--base DIR --new DIR]

--base / --new: folders holding a bvhlab package with its _core module (python/ of a source tree
and the built .so); each variant runs in a process of its own per round with only that folder and
the virtual environment's site-packages on its path (python -S: the editable install's hook
would import this tree's bvhlab whatever PYTHONPATH says). Without them, this tree's bvhlab.
Stack and stackless; the median over the rounds and the ratio to the base (or to counters off).
Wall times on a shared machine vary by tens of percent from round to round: --callgrind N also
counts the instructions of N frames (stack and stackless, one thread) per variant under callgrind,
less those of a run with no frame, which resolves about 1%. Writes bench/results/counters_cost.json.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _common  # noqa: E402

_CHILD = """
import json, sys, time
import bvhlab
from bvhlab.library import load_scene
scene, _ = load_scene(sys.argv[1])
scene = scene.flattened()
bvh = bvhlab.build(scene)
w, h, frames, counters = int(sys.argv[2]), int(sys.argv[3]), int(sys.argv[4]), sys.argv[5] == "1"
out = {}
for traversal in ("stack", "stackless"):
    kw = dict(traversal=traversal, threads=1)
    if counters:
        kw["traversal_counters"] = True
    bvhlab.render(scene, bvh, w, h, backend="cpu", **kw)  # warm-up
    times = []
    for _ in range(frames):
        _, t = bvhlab.render(scene, bvh, w, h, backend="cpu", **kw)
        times.append(t["trace_ms"])
    out[traversal] = min(times)
print(json.dumps({"file": bvhlab.__file__, **out}))
"""


def _run(folder: str | None, args, counters: bool) -> dict:
    env, isolate = dict(os.environ), []
    if folder:
        site = next(p for p in sys.path if p.endswith("site-packages"))
        env["PYTHONPATH"] = os.pathsep.join([str(Path(folder).resolve()), site])
        isolate = ["-S"]
    cmd = [sys.executable, *isolate, "-c", _CHILD, args.scene, str(args.width), str(args.height), str(args.frames)]
    res = subprocess.run([*cmd, "1" if counters else "0"], env=env, capture_output=True, text=True, check=True)
    return json.loads(res.stdout.strip().splitlines()[-1])


_CALLGRIND_CHILD = """
import sys
import bvhlab
from bvhlab.library import load_scene
scene, _ = load_scene(sys.argv[1])
bvh = bvhlab.build(scene, threads=1)
w, h, frames, counters = int(sys.argv[2]), int(sys.argv[3]), int(sys.argv[4]), sys.argv[5] == "1"
kw = {"traversal_counters": True} if counters else {}
for traversal in ("stack", "stackless"):
    for _ in range(frames):
        bvhlab.render(scene, bvh, w, h, backend="cpu", traversal=traversal, threads=1, **kw)
"""


def _instructions(folder: str | None, args, counters: bool, frames: int) -> int:
    env, isolate = dict(os.environ), []
    if folder:
        site = next(p for p in sys.path if p.endswith("site-packages"))
        env["PYTHONPATH"] = os.pathsep.join([str(Path(folder).resolve()), site])
        isolate = ["-S"]
    cmd = ["valgrind", "--tool=callgrind", "--callgrind-out-file=/dev/null", sys.executable, *isolate]
    cmd += ["-c", _CALLGRIND_CHILD, args.scene, str(args.width), str(args.height), str(frames), str(int(counters))]
    res = subprocess.run(cmd, env=env, capture_output=True, text=True, check=True)
    return int(next(line for line in res.stderr.splitlines() if "Collected" in line).split()[-1])


def _callgrind(variants: dict, args) -> dict:
    out = {}
    for name, (path, counters) in variants.items():
        n = _instructions(path, args, counters, args.callgrind) - _instructions(path, args, counters, 0)
        out[name] = n / args.callgrind
        print(f"callgrind {name}: {out[name] / 1e6:.2f} M instructions a frame pair (stack + stackless)", flush=True)
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scene", default="atrium")
    ap.add_argument("--width", type=int, default=320)
    ap.add_argument("--height", type=int, default=240)
    ap.add_argument("--frames", type=int, default=3, help="frames per process (the fastest is kept)")
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--base", help="folder of a bvhlab built before the counters")
    ap.add_argument("--new", help="folder of this tree's bvhlab (with --base: both isolated alike)")
    ap.add_argument("--callgrind", type=int, default=0, help="frames counted under callgrind (0: none)")
    args = ap.parse_args()
    variants = {"off": (args.new, False), "on": (args.new, True)}
    if args.base:
        variants = {"base": (args.base, False), **variants}
    runs: dict[str, list[dict]] = {k: [] for k in variants}
    for r in range(args.rounds):
        for name, (path, counters) in variants.items():
            runs[name].append(_run(path, args, counters))
            print(f"round {r + 1} {name}: {runs[name][-1]}", flush=True)
    reference = "base" if args.base else "off"
    instructions = _callgrind(variants, args) if args.callgrind else {}
    table = {}
    for name, rs in runs.items():
        table[name] = {t: statistics.median(r[t] for r in rs) for t in ("stack", "stackless")}
    for name in table:
        table[name]["ratio_stack"] = table[name]["stack"] / table[reference]["stack"]
        table[name]["ratio_stackless"] = table[name]["stackless"] / table[reference]["stackless"]
        print(f"{name:5s} " + "  ".join(f"{k} {v:.3f}" for k, v in table[name].items()))
    _common.write_json(
        "counters_cost.json",
        {
            "machine": _common.machine(),
            "scene": args.scene,
            "size": [args.width, args.height],
            "threads": 1,
            "rounds": args.rounds,
            "note": "trace ms, CPU reference, one thread, median over interleaved rounds of the fastest of "
            f"{args.frames} frames; the machine is shared with other jobs",
            "reference": reference,
            "median_trace_ms": table,
            "runs": runs,
            "callgrind_instructions_per_frame_pair": instructions,
            "callgrind_ratio": {k: v / instructions[reference] for k, v in instructions.items()},
        },
    )


if __name__ == "__main__":
    main()
