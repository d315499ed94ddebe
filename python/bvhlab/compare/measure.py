"""Build and render a scene with each split method: the numbers behind Table 1."""
from __future__ import annotations

import statistics
from typing import Callable

from ..bvh import build
from ..bvh import method_from_label as method_kwargs  # 'sah32' → sah with 32 bins
from ..render import Renderer
from ..scene import Scene


def measure_methods(scene: Scene, labels: list[str], *, frames: int = 5, builds: int = 5, width: int = 800,
                    height: int = 600, renderer: Renderer | None = None, samples_per_axis: int = 1, max_depth: int = 5,
                    build_options: dict | None = None, render_options: dict | None = None,
                    progress: Callable[[str], None] | None = None) -> list[dict]:
    """For each method: build time (median of `builds` builds), average frame time over `frames`
    frames after one warm-up frame (the report's protocol: same camera, 800×600), and the tree's
    height, SAH cost, nodes and leaves. A frame is the overlay pass, the trace pass and the read
    back (our stand-in for the report's present). `build_options`: axis, max_leaf_size, ...;
    `render_options`: traversal, ..."""
    renderer = renderer or Renderer("auto")
    rows = []
    for label in labels:
        kwargs = {**(build_options or {}), **method_kwargs(label)}
        if progress:
            progress(f"{label}: building")
        trees = [build(scene, **kwargs) for _ in range(max(1, builds))]
        bvh = trees[-1]
        stats = bvh.stats
        if progress:
            progress(f"{label}: rendering {frames} frames")
        options = {"samples_per_axis": samples_per_axis, "max_depth": max_depth, **(render_options or {})}
        renderer.render(scene, bvh, width, height, **options)  # warm-up (and upload)
        frame_ms = []
        for _ in range(max(1, frames)):
            _, t = renderer.render(scene, bvh, width, height, **options)
            frame_ms.append(t["overlay_ms"] + t["trace_ms"] + t["readback_ms"])
        mean_frame = statistics.fmean(frame_ms)
        rows.append({
            "method": label, "split_method": kwargs["method"], "bins": kwargs.get("bins"),
            "frame_ms": mean_frame, "frame_ms_all": frame_ms,
            "build_ms": statistics.median(t.stats["build_ms"] for t in trees),
            "height": stats["height"], "sah_cost": stats["sah_cost"], "nodes": stats["nodes"],
            "leaves": stats["leaves"], "nodes_per_depth": stats["nodes_per_depth"],
            "primary_mrays_s": width * height * samples_per_axis ** 2 / (mean_frame * 1e3),
            "device": t["device"], "backend": t["backend"],
        })
    return rows
