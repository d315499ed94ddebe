"""`bvhlab animate ANIMATION --frames A-B --policy rebuild,refit,partial,adaptive --out DIR`: the
per-frame dynamic-BVH experiment the report could not run (issue 34; bvhlab.animate). ANIMATION is
a generated one (wave, crowd) or an animated `.blend` file (each frame set and exported through
bpy as the add-on does, its instancing kept: blender_scenes/make_animated.py makes two). Per frame
and policy: update ms, the policy adaptive chose, SAH cost against a fresh build's, subtrees
rebuilt, and with --backend the frame's trace time; an instanced scene adds its two-level tree's
update time. Writes animate.csv, animate.json and animate.png (the SAH ratio and the update time
over the frames)."""

from __future__ import annotations

import argparse
import csv
import io
import math
import re
import sys
from collections.abc import Callable
from pathlib import Path

import numpy as np

from .. import _json as strict_json
from .._atomic import write_together
from .._folder_lock import folder_lock
from .._progress import ProgressBar
from ..animate import FrameRow, as_scene, run_experiment, summary
from ..library.animations import ANIMATION_FRAMES, ANIMATIONS, frame_phase
from ..render import BACKENDS
from ..render_options import DEFAULT_HEIGHT, DEFAULT_WIDTH
from ..scene import Scene
from ..update import UPDATE_POLICIES
from . import options
from .compare_args import output_dir

#: The most frames one run takes (the CLI's other per-frame limits are the same).
MAX_FRAMES = 10_000


def add_parser(sub) -> None:
    p = sub.add_parser("animate", help="update policies frame by frame over an animation", description=__doc__)
    p.add_argument(
        "animation",
        type=animation_spec,
        help="; ".join(f"{k}: {v[1]}" for k, v in ANIMATIONS.items()) + "; or an animated .blend file",
    )
    p.add_argument(
        "--frames",
        type=frame_range,
        default=None,
        metavar="A-B",
        help="frames A..B (default 0-23, the generated animations' motion, the same frame in any range; "
        "a .blend: its range)",
    )
    p.add_argument("--policy", type=policy_list, default=UPDATE_POLICIES, metavar="P,Q", help="policies (default all)")
    p.add_argument(
        "--size",
        type=lambda t: options.whole_number(t, 2, 4096),
        default=None,
        help="the animation's size (wave: quads per side; crowd: knots), smaller for a quick run",
    )
    p.add_argument("--backend", default="none", choices=("none", *BACKENDS), help="trace each frame (default: none)")
    options.add_image_size(p, defaults=False)  # the traced frames' (--backend), by default 800 × 600
    p.add_argument("--out", type=output_dir, required=True, metavar="DIR")
    p.set_defaults(run=run)


def frame_range(text: str) -> range:
    """'0-23' → range(0, 24). ASCII digits only (int() also took '1_0' and other scripts' digits)."""
    match = re.fullmatch(r"([0-9]+)-([0-9]+)", text)
    if match is None:
        raise argparse.ArgumentTypeError(f"frames must look like A-B (e.g. 0-23), got '{text}'")
    a, b = int(match[1]), int(match[2])
    if not 0 <= a < b:
        raise argparse.ArgumentTypeError(f"frames {text}: need 0 <= A < B")
    if b - a + 1 > MAX_FRAMES:
        raise argparse.ArgumentTypeError(f"frames {text}: at most {MAX_FRAMES} frames")
    return range(a, b + 1)


def animation_spec(text: str) -> str:
    if text in ANIMATIONS or (Path(text).suffix.lower() == ".blend" and Path(text).is_file()):
        return text
    raise argparse.ArgumentTypeError(f"'{text}' is neither one of {', '.join(ANIMATIONS)} nor an existing .blend file")


def policy_list(text: str) -> tuple[str, ...]:
    names = tuple(dict.fromkeys(n.strip() for n in text.split(",") if n.strip()))
    bad = [n for n in names if n not in UPDATE_POLICIES]
    if bad or not names:
        raise argparse.ArgumentTypeError(f"policies are among {', '.join(UPDATE_POLICIES)}; got '{text}'")
    return names


def _frames_of(args) -> tuple[Callable[[int], np.ndarray | Scene], range]:
    """Frame k's geometry, and the frames to run."""
    if Path(args.animation).suffix.lower() == ".blend":
        if args.size is not None:  # was ignored, and written into animate.json as if used
            raise ValueError("--size sizes the generated animations (wave, crowd); a .blend is run as it is")
        from ..blender.animation import open_animation

        scene_at, frames = open_animation(Path(args.animation))
        if args.frames and (args.frames[0] < frames[0] or args.frames[-1] > frames[-1]):
            print(
                f"note: frames {args.frames[0]}-{args.frames[-1]} reach outside {args.animation}'s frame range "
                f"{frames[0]}-{frames[-1]} (what it shows there is what its keyframes give)",
                file=sys.stderr,
            )
        return scene_at, args.frames or frames
    make = ANIMATIONS[args.animation][0]
    frame_of = make(args.size) if args.size else make()
    # frame k is the same geometry whatever the range run (a .blend's frames are too): spread over
    # the range asked for, frame 12 of 12-23 was frame 0 and a shorter range moved more a frame
    last = ANIMATION_FRAMES - 1
    return (lambda k: frame_of(frame_phase(k, 0, last))), args.frames or range(0, last + 1)


#: The files a run writes into --out, and what each is (for the messages).
OUTPUTS = (("animate.csv", "table"), ("animate.json", "report"), ("animate.png", "plot"))


def run(args) -> int:
    if args.backend == "none" and (args.width or args.height):  # they were accepted and ignored
        raise ValueError("--width and --height size the traced frames: give --backend cpu, vulkan or auto")
    args.width, args.height = args.width or DEFAULT_WIDTH, args.height or DEFAULT_HEIGHT
    geometry, frames = _frames_of(args)
    if len(frames) < 2:  # before the folder is made (an empty one was left) and any work
        raise ValueError(f"the experiment needs at least two frames, got {len(frames)}")
    # the three files' names, before the experiment (a folder named animate.png was found after it)
    outputs = {name: args.out / name for name, _ in OUTPUTS}
    for name, what in OUTPUTS:
        if outputs[name].is_dir():
            raise ValueError(f"{outputs[name]} is a folder: the run writes its {what} there (move the folder away)")
    first, last = frames[0], frames[-1]
    trace = None
    if args.backend != "none":
        from ..render import Camera, render

        lo, hi = as_scene(geometry(first)).bounds()
        centre = (float(lo[0] + hi[0]) / 2, float(lo[1] + hi[1]) / 2, float(lo[2] + hi[2]) / 2)
        extent = float(max(hi - lo))
        eye = (centre[0] - 0.2 * extent, centre[1] - 1.1 * extent, centre[2] + 0.8 * extent)
        camera = Camera(eye, centre, fov_y=45)

        def trace(geometry, bvh) -> float:
            scene = Scene(triangles=geometry.triangles, spheres=geometry.spheres, camera=camera)
            _, t = render(scene, bvh, args.width, args.height, backend=args.backend)
            return float(t["trace_ms"])

    args.out.mkdir(parents=True, exist_ok=True)
    # one run at a time in a folder (a second is refused at once, naming the first), and its three
    # files all or none (an interrupt while the plot was drawn left the new table and report
    # beside the old plot)
    with folder_lock(args.out, "bvhlab animate"):
        with ProgressBar(f"{args.animation}, {len(frames)} frames × {len(args.policy)} policies") as bar:
            rows = run_experiment(geometry, frames, args.policy, trace=trace, progress=bar)
        totals = summary(rows)
        about = {"animation": args.animation, "size": args.size, "frames": [first, last], "backend": args.backend}
        report = {"about": about, "summary": totals, "rows": [r.as_dict() for r in rows]}
        plot = _plot(rows, f"{Path(args.animation).stem}: update policies over frames {first}-{last}")
        write_together(
            {
                outputs["animate.csv"]: _csv(rows).encode(),
                outputs["animate.json"]: (strict_json.dumps(report, indent=1) + "\n").encode(),
                outputs["animate.png"]: plot,
            }
        )
    _print(rows, totals)  # after the files: a reader gone (`| head`) lost them
    print(f"wrote {args.out / 'animate.csv'}, animate.json, animate.png")
    return 0


def _csv(rows: list[FrameRow]) -> str:
    out = io.StringIO()
    fields = list(rows[0].as_dict())
    writer = csv.DictWriter(out, fieldnames=fields, lineterminator="\n")
    writer.writeheader()
    for r in rows:
        writer.writerow(r.as_dict())
    return out.getvalue()


def _print(rows: list[FrameRow], totals: dict) -> None:
    policies = list(dict.fromkeys(r.policy for r in rows))
    print(f"{'frame':>5}  " + "  ".join(f"{p + ' ms / SAH÷fresh':>28}" for p in policies))
    for k in dict.fromkeys(r.frame for r in rows):
        cells = []
        for p in policies:
            r = next(r for r in rows if r.frame == k and r.policy == p)
            cells.append(f"{r.update_ms:9.2f} {_ratio(r.sah_ratio):>6} {r.ran[:8]:>10}")
        print(f"{k:>5}  " + "  ".join(f"{c:>28}" for c in cells))
    for p, t in totals.items():
        share = f", {t['share_of_rebuild']:.2f} of rebuilding every frame" if "share_of_rebuild" in t else ""
        print(f"{p}: {t['total_ms']:.1f} ms in all{share}; SAH ÷ fresh worst {_ratio(t['worst_sah_ratio'])}")


def _ratio(value: float) -> str:
    """A SAH ratio for the table; "–" where none was measured (the two-level rows: NaN in the JSON)."""
    return "–" if math.isnan(value) else f"{value:.3f}"


def _plot(rows: list[FrameRow], title: str) -> bytes:
    """The plot as PNG bytes: SAH ÷ a fresh build's and update ms, frame by frame, by policy."""
    from ..compare.charts import _figure_bytes, _plt

    plt = _plt()
    fig, (left, right) = plt.subplots(1, 2, figsize=(10, 3.8))
    for p in dict.fromkeys(r.policy for r in rows):
        mine = [r for r in rows if r.policy == p and r.ran != "build"]
        frames = [r.frame for r in mine]
        if not all(math.isnan(r.sah_ratio) for r in mine):  # the two-level row has no flat SAH
            left.plot(frames, [r.sah_ratio for r in mine], marker=".", label=p)
        right.plot(frames, [r.update_ms for r in mine], marker=".", label=p)
    left.set_ylabel("SAH cost ÷ a fresh build's")
    right.set_ylabel("update (ms)")
    right.set_yscale("log" if any(r.update_ms > 0 for r in rows) else "linear")
    for ax in (left, right):
        ax.set_xlabel("frame")
        ax.legend(fontsize=8)
    fig.suptitle(title)
    return _figure_bytes(fig, plt)  # written with the table and the report: write_together
