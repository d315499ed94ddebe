"""Two trees side by side (issue 35): one traversal counter per pixel of the same view rendered
with each tree, both next to each other on the heat ramp over one range, and their difference
(first minus second) on the diverging ramp (white 0, red where the first tree costs more, blue
where it costs less) with its scale bar, plus the mean and percentiles of each and of the
difference."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .. import _json as strict_json
from .. import counters, legend, palette
from .._atomic import replacing
from ..png import save_png
from ..render import Renderer
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
    value_range: tuple[float, float] | None = None,
) -> dict:
    """`counter` of each tree, their difference a − b, its image with a legend (span None: auto,
    counters.auto_span), both trees' counters side by side (side_by_side, over `value_range`) and a
    summary: {"a", "b", "difference", "image", "span", "side_by_side", "summary"}."""
    a, b = counter_planes(
        scene, (bvh_a, bvh_b), counter, width, height, renderer=renderer, options=options, camera=camera
    )
    difference = a - b
    image, span = counters.difference_image(difference, span)
    pair, (lo, hi) = side_by_side(a, b, value_range)
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
        "side_by_side_range": [lo, hi],
    }
    return {
        "a": a,
        "b": b,
        "difference": difference,
        "image": image,
        "span": span,
        "side_by_side": pair,
        "summary": summary,
    }


#: Pixels between the two trees' images side by side.
GAP = 4


def side_by_side(a: np.ndarray, b: np.ndarray, value_range: tuple[float, float] | None = None):
    """The two trees' (H, W) counter planes next to each other (first left) on the heat ramp over
    one range (None: the auto range of both together), GAP pixels of legend background between
    them, one scale bar under both; returns (image, (lo, hi))."""
    lo, hi = counters.auto_range(np.concatenate([a.ravel(), b.ravel()])) if value_range is None else value_range
    counters.check_range(lo, hi)
    gap = legend.blank_strip(a.shape[0], GAP)
    top = np.concatenate([palette.heat_image(a, lo, hi), gap, palette.heat_image(b, lo, hi)], axis=1)
    return legend.below(top, legend.heat_bar(top.shape[1], lo, hi)), (float(lo), float(hi))


def write_difference(result: dict, out: Path, stem: str) -> dict:
    """STEM.png (the difference image with its legend), STEM_side_by_side.png (both trees' counters),
    STEM.npy ((3, H, W): first, second, difference) and STEM.json (the summary) in `out`; returns
    their paths."""
    paths = {
        "png": out / f"{stem}.png",
        "side_by_side": out / f"{stem}_side_by_side.png",
        "npy": out / f"{stem}.npy",
        "json": out / f"{stem}.json",
    }
    save_png(result["image"], paths["png"])
    save_png(result["side_by_side"], paths["side_by_side"])
    with replacing(paths["npy"]) as f:
        np.save(f, np.stack([result["a"], result["b"], result["difference"]]))
    with replacing(paths["json"], text=True) as f:
        f.write(strict_json.dumps(result["summary"], indent=2))
    return paths
