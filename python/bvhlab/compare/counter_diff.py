"""Two trees side by side (issue 35): one traversal counter per pixel of the same view rendered
with each tree, and their difference (first minus second) on the diverging ramp (white 0, red
where the first tree costs more, blue where it costs less) with its scale bar, plus the mean and
percentiles of each and of the difference."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from .. import counters
from .._atomic import replacing
from ..render import Renderer, save_png
from ..render_options import options_from


def build_trees(scene, labels, build_options: dict | None = None) -> list:
    """The tree of each method label over `scene`, built as `bvhlab compare` builds its rows (the
    report's settings, measure.build_settings, with `build_options` over them; every core)."""
    from .. import build
    from .measure import build_settings

    return [build(scene, **{**build_settings(label, build_options), "threads": 0}) for label in labels]


def counter_planes(
    scene, bvhs, counter: str, width: int, height: int, *, renderer: Renderer, options=None, camera=None
):
    """One (H, W) plane of `counter` per tree in `bvhs`, each from a render of the same view."""
    counters.counter_index(counter)  # an unknown name fails before any render
    opts = options_from(options, {}).replace(traversal_counters=True)
    planes = []
    for bvh in bvhs:
        job = renderer.start(scene, bvh, width, height, options=opts, camera=camera)
        job.run()
        kept = job.result(color=False, depth=False, cost=False, counters=True).counters
        assert kept is not None  # asked for
        planes.append(counters.counter_plane(kept, counter))
    return planes


def counter_difference(
    scene,
    bvh_a,
    bvh_b,
    counter: str,
    width: int,
    height: int,
    *,
    renderer: Renderer,
    labels=("a", "b"),
    options=None,
    camera=None,
    span: float | None = None,
) -> dict:
    """`counter` of each tree, their difference a − b, its image with a legend (span None: auto,
    counters.auto_span) and a summary: {"a", "b", "difference", "image", "span", "summary"}."""
    a, b = counter_planes(
        scene, (bvh_a, bvh_b), counter, width, height, renderer=renderer, options=options, camera=camera
    )
    difference = a - b
    image, span = counters.difference_image(difference, span)
    summary = {
        "counter": counter,
        "first": labels[0],
        "second": labels[1],
        "difference": f"{labels[0]} - {labels[1]}",
        "span": span,
        "auto_percentile": counters.AUTO_PERCENTILE,
        labels[0]: counters.summary(a),
        labels[1]: counters.summary(b),
        "first_minus_second": counters.summary(difference),
        "pixels_first_more": int((difference > 0).sum()),
        "pixels_first_less": int((difference < 0).sum()),
    }
    return {"a": a, "b": b, "difference": difference, "image": image, "span": span, "summary": summary}


def write_difference(result: dict, out: Path, stem: str) -> dict:
    """STEM.png (the difference image with its legend), STEM.npy ((3, H, W): first, second,
    difference) and STEM.json (the summary) in `out`; returns their paths."""
    paths = {"png": out / f"{stem}.png", "npy": out / f"{stem}.npy", "json": out / f"{stem}.json"}
    save_png(result["image"], paths["png"])
    with replacing(paths["npy"]) as f:
        np.save(f, np.stack([result["a"], result["b"], result["difference"]]))
    with replacing(paths["json"], text=True) as f:
        f.write(json.dumps(result["summary"], indent=2))
    return paths
