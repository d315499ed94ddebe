"""Build and render a scene with each split method: the numbers behind Table 1, taken with the
protocol of `protocol.py` (warm-up round, interleaved rounds, medians with their intervals)."""

from __future__ import annotations

import time
from collections.abc import Callable

from ..build_config import BINNED_METHODS
from ..build_config import method_from_label as method_kwargs  # 'sah32' → sah with 32 bins
from ..bvh import build
from ..instanced import InstancedBvh
from ..render import Renderer
from ..render_options import DEFAULT_HEIGHT, DEFAULT_WIDTH, RenderOptions
from ..scene import Scene
from ..two_level_stats import two_level_sah_cost_per_depth
from .protocol import DEFAULT_BUILDS, DEFAULT_FRAMES, median_interval, rounds, sample_count
from .report import TWO_LEVEL_COLUMNS
from .tree_stats import sah_cost_per_depth

#: The report's build settings (§2.3, §4.2), stated here rather than taken from the library's
#: defaults: one primitive per leaf, the axis of largest centroid extent, SAH buckets over the
#: centroid bounds and primitives counted one by one (§2.3.2, eq. 1); the bins come from the
#: method label (sah12, sah32). Builds run on one thread, like the report's builder.
REPORT_BUILD = {"axis": "largest", "max_leaf_size": 1, "bin_bounds": "centroids", "sah_block": 1, "threads": 1}
DEFAULT_BINS = 12  # the report's (PBRT's) value, for a bare "sah"


def build_settings(label: str, build_options: dict | None = None) -> dict:
    """Every argument of `bvhlab.build` for a method label, none left to the library's defaults."""
    kwargs = {**REPORT_BUILD, "bins": DEFAULT_BINS, **(build_options or {}), **method_kwargs(label)}
    kwargs.setdefault("seed", 0)
    return kwargs


def render_frame(
    renderer: Renderer,
    scene: Scene,
    bvh,
    width: int,
    height: int,
    options: RenderOptions | None = None,
    threads: int = 0,
    **option_changes,
):
    """The one place compare calls the tracer, with `options` (default RenderOptions()) and any of
    its fields by name on top. Returns (image, wall ms, CPU ms, timings): a frame is
    the overlay pass, the trace pass and the read-back (our stand-in for the report's present); its
    CPU time is that of every thread of this process during the call (the CPU reference's,
    lavapipe's). Nothing is subtracted from it: the timings are wall clock, and under load a wall
    time exceeds the CPU time it spans. Each tree has a renderer of its own (_render_rounds), whose
    scene the warm-up round made and uploaded, so a counted frame's CPU time is the frame's own."""
    cpu_start = time.process_time()
    image, t = renderer.render(scene, bvh, width, height, options=options, threads=threads, **option_changes)
    cpu_ms = (time.process_time() - cpu_start) * 1e3
    return image, t["overlay_ms"] + t["trace_ms"] + t["readback_ms"], cpu_ms, t


def frame_clock(renderer: Renderer) -> str:
    """ "cpu" where the frames run on this machine's CPU (the CPU reference, a CPU Vulkan driver such
    as lavapipe): there the process's CPU time measures a frame's work, while wall time also
    measures whoever else uses the cores. "wall" for a GPU, whose work no CPU clock sees."""
    if renderer.backend == "cpu":
        return "cpu"
    device_type = getattr(renderer, "device_type", None) or getattr(
        getattr(renderer, "_vulkan", None), "device_type", ""
    )
    return "cpu" if device_type == "cpu" else "wall"


def timed_build(scene: Scene, settings: dict):
    """(tree, CPU ms of the build): builds run on the CPU, so CPU time is their cost."""
    start = time.process_time()
    bvh = build(scene, **settings)
    return bvh, (time.process_time() - start) * 1e3


def measure_methods(
    scene: Scene,
    labels: list[str],
    *,
    frames: int = DEFAULT_FRAMES,
    builds: int = DEFAULT_BUILDS,
    width: int = DEFAULT_WIDTH,
    height: int = DEFAULT_HEIGHT,
    renderer: Renderer | None = None,
    options: RenderOptions | None = None,
    threads: int = 0,
    build_options: dict | None = None,
    progress: Callable[[str], None] | None = None,
) -> list[dict]:
    """For each method: `builds` build times and `frames` frame times, each after a warm-up that is
    not counted, taken in interleaved rounds; reported as medians with their intervals, in wall
    time (frame_ms, frame_ms_lo, frame_ms_hi, frame_ms_all; build_ms, ...) and in CPU time
    (frame_cpu_ms, ...; build_cpu_ms, ...), every sample kept in round order (paired across
    methods). `frame_clock` says which clock measures a frame's work (`frame_clock()`); builds
    are always measured by CPU time. Plus the tree's height, SAH cost, nodes, leaves, per depth.
    `build_options` override the report's settings (REPORT_BUILD); `options` (a RenderOptions) how
    each frame is traced, `threads` the CPU reference's.
    `frames` and `builds` are 1 to MAX_SAMPLES (ValueError otherwise, before any work)."""
    if len(set(labels)) != len(labels) or not labels:
        raise ValueError(f"methods must be distinct and at least one, got {labels}")
    frames, builds = sample_count("frames", frames), sample_count("builds", builds)
    renderer = renderer or Renderer("auto")
    say = progress or (lambda text: None)
    settings = {label: build_settings(label, build_options) for label in labels}
    trees, build_times = _build_rounds(scene, settings, builds, say)
    options = options or RenderOptions()
    frame_times, timings = _render_rounds(scene, trees, frames, width, height, renderer, (options, threads), say)
    rows = []
    for label in labels:
        row = _row(label, settings[label], trees[label], timings[label])
        row.update(samples_columns("frame", *frame_times[label]), frame_clock=frame_clock(renderer))
        row.update(samples_columns("build", *build_times[label]))
        row["primary_mrays_s"] = width * height * options.samples / (row["frame_ms"] * 1e3)
        rows.append(row)
    return rows


def samples_columns(name: str, wall_ms: list[float], cpu_ms: list[float]) -> dict:
    """<name>_ms (wall) and <name>_cpu_ms: median, _lo, _hi (its interval) and _all (every sample)."""
    out = {}
    for key, samples in ((f"{name}_ms", wall_ms), (f"{name}_cpu_ms", cpu_ms)):
        interval = median_interval(samples)
        out.update(
            {key: interval.median, f"{key}_lo": interval.lo, f"{key}_hi": interval.hi, f"{key}_all": list(samples)}
        )
    return out


def _build_rounds(scene, settings: dict, builds: int, say) -> tuple[dict, dict]:
    """Trees of the warm-up round (not counted), and per label ([wall ms], [CPU ms]) of the rest."""
    labels = list(settings)
    trees: dict = {}
    times: dict[str, tuple[list[float], list[float]]] = {label: ([], []) for label in labels}
    for label in labels:
        say(f"{label}: building")
        trees[label] = build(scene, **settings[label])
    for r, order in enumerate(rounds(labels, builds)):
        say(f"builds: round {r + 1}/{builds}")
        for label in order:
            bvh, cpu_ms = timed_build(scene, settings[label])
            times[label][0].append(bvh.stats["build_ms"])
            times[label][1].append(cpu_ms)
    return trees, times


def _render_rounds(scene, trees: dict, frames: int, width, height, renderer, options: tuple, say):
    """Per label ([wall ms], [CPU ms]) of the counted frames, and the timings of its last frame.
    `options`: (RenderOptions, threads)."""
    labels = list(trees)
    times: dict[str, tuple[list[float], list[float]]] = {label: ([], []) for label in labels}
    last: dict = {}
    # a renderer each: one renderer keeps one scene, so frames taken in turn made and uploaded
    # theirs again every time, inside the CPU time (Sponza: ~18 ms a frame against 2 for the
    # same tree again; review of the reproduction)
    renderers = {label: renderer.like() for label in labels}
    for label in labels:  # warm-up round (the scene made and uploaded, shaders, caches), not counted
        say(f"{label}: warm-up frame")
        render_frame(renderers[label], scene, trees[label], width, height, *options)
    for r, order in enumerate(rounds(labels, frames)):
        say(f"frames: round {r + 1}/{frames}")
        for label in order:
            frame = render_frame(renderers[label], scene, trees[label], width, height, *options)
            _, wall_ms, cpu_ms, last[label] = frame
            times[label][0].append(wall_ms)
            times[label][1].append(cpu_ms)
    return times, last


def _row(label, settings, bvh, timings) -> dict:
    stats = bvh.stats
    row = {
        "method": label,
        "split_method": settings["method"],
        "bins": settings["bins"] if settings["method"] in BINNED_METHODS else None,  # as Bvh.stats
        "build_settings": settings,
        "height": stats["height"],
        "sah_cost": stats["sah_cost"],
        "nodes": stats["nodes"],
        "leaves": stats["leaves"],
        "device": timings["device"],
        "backend": timings["backend"],
        "traversal": timings["traversal"],  # the walk that rendered the frames
        # where the last counted frame's time went (frame_ms is overlay + trace + read-back; making and
        # uploading its scene, prepare_ms and upload_ms, is outside it and ~0 once warm)
        "last_frame": {
            k: timings[k]
            for k in ("overlay_ms", "trace_ms", "readback_ms", "dispatches", "prepare_ms", "upload_ms")
            if k in timings
        },
    }
    if isinstance(bvh, InstancedBvh):  # the TLAS's numbers, and the meshes' trees' (each once)
        row.update({name: stats[name] for name in TWO_LEVEL_COLUMNS})
        row["nodes_per_depth"] = _summed([m.stats["nodes_per_depth"] for m in bvh.meshes])
        row["leaf_size_histogram"] = _summed([m.stats["leaf_size_histogram"] for m in bvh.meshes])
        row["sah_cost_per_depth"] = two_level_sah_cost_per_depth(
            bvh.tlas, bvh.instances[0], [sah_cost_per_depth(m) for m in bvh.meshes], stats["mesh_sah_cost"]
        )  # by depth in the tree TLAS and BLASes make together (two_level_stats.py)
    else:
        row["nodes_per_depth"] = stats["nodes_per_depth"]
        row["leaf_size_histogram"] = stats["leaf_size_histogram"]
        row["sah_cost_per_depth"] = sah_cost_per_depth(bvh)
    return row


def _summed(lists: list[list]) -> list:
    """Elementwise sums of lists of different lengths."""
    out = [0] * max((len(x) for x in lists), default=0)
    for x in lists:
        for i, v in enumerate(x):
            out[i] += v
    return out
