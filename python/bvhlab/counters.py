"""Traversal counters per pixel (issue 35; the traversal counters of AMD's Radeon Raytracing
Analyzer): box tests, box hits, primitive tests, primitive hits and instance hits of each pixel's
primary rays, averaged over its samples. Counted by the tracer itself (shaders/tracer/
traverse.glsl), the same on the CPU reference and on Vulkan; reflection, refraction and shadow
rays are not counted, so a pixel's counters are those `bvhlab.inspect.ray_record.trace_pixel`
records for it with the stack or stackless walk (a surface hidden from camera rays passed by in
both; the wide walk's record does not pass it by, and warns).

The names come from the core's TraversalCounter enum (render_settings.h); this module adds the
ranges and images: a manual range, or the auto range (0 to the AUTO_PERCENTILE-th percentile of
the image), and the false-colour image on the heat ramp with its scale bar."""

from __future__ import annotations

import numpy as np

from . import _core, legend, palette
from ._checks import FLOAT32_MAX

#: Counter names in the core's order (RenderResult.counters' last axis).
COUNTERS: tuple[str, ...] = tuple(_core.TRAVERSAL_COUNTERS)
LABELS = {
    "box_tests": "Box tests",
    "box_hits": "Box hits",
    "prim_tests": "Primitive tests",
    "prim_hits": "Primitive hits",
    "instance_hits": "Instance hits",
}
#: The auto range's top: this percentile of the image's values (the few costliest pixels saturate
#: instead of squeezing the rest into the blue end).
AUTO_PERCENTILE = 99.0


def counter_index(name: str) -> int:
    """The position of counter `name` (ValueError listing the names for an unknown one)."""
    if not isinstance(name, str):
        raise TypeError(f"counter must be a string, got {type(name).__name__}")
    return int(_core.parse_traversal_counter(name).value)


def counter_plane(counters: np.ndarray, name: str) -> np.ndarray:
    """(H, W) float32: counter `name` of a RenderResult's (H, W, 5) counters."""
    return np.ascontiguousarray(counters[..., counter_index(name)])


def auto_range(values: np.ndarray) -> tuple[float, float]:
    """(0, the AUTO_PERCENTILE-th percentile of `values`), the top at least 1."""
    return range_to(float(np.percentile(values, AUTO_PERCENTILE)) if values.size else 0.0)


def range_to(top: float) -> tuple[float, float]:
    """The auto range whose percentile is `top`: 0 to top, at least 1."""
    return 0.0, max(top, 1.0)


def auto_span(difference: np.ndarray) -> float:
    """± range of a difference image: the AUTO_PERCENTILE-th percentile of |difference|, at least 1."""
    top = float(np.percentile(np.abs(difference), AUTO_PERCENTILE)) if difference.size else 0.0
    return max(top, 1.0)


def parse_range(text: str) -> tuple[float, float] | None:
    """'LO,HI' → (lo, hi) with lo < hi, both finite; 'auto' → None (ValueError otherwise)."""
    if text.strip() == "auto":
        return None
    parts = text.split(",")
    try:
        lo, hi = (float(p) for p in parts)
    except ValueError:
        raise ValueError(f"range must be LO,HI (two numbers) or auto, got {text!r}") from None
    check_range(lo, hi)
    return lo, hi


def check_range(lo: float, hi: float) -> None:
    if not (np.isfinite(lo) and np.isfinite(hi) and lo < hi):
        raise ValueError(f"range must be two finite numbers LO < HI, got {lo}, {hi}")
    # the counters and their scale are float32 (1e40 overflowed in the histogram's grid)
    if max(abs(lo), abs(hi)) > FLOAT32_MAX or not np.float32(lo) < np.float32(hi):
        raise ValueError(f"range must be two numbers LO < HI that float32 tells apart, got {lo:g}, {hi:g}")


def counter_image(values: np.ndarray, value_range: tuple[float, float] | None = None) -> tuple[np.ndarray, tuple]:
    """The (H + legend, W, 4) false-colour image of an (H, W) counter plane on the heat ramp over
    `value_range` (None: auto_range), with its scale bar below; returns (image, (lo, hi))."""
    lo, hi = auto_range(values) if value_range is None else value_range
    check_range(lo, hi)
    image = palette.heat_image(values, lo, hi)
    return legend.below(image, legend.heat_bar(values.shape[1], lo, hi)), (lo, hi)


def difference_image(difference: np.ndarray, span: float | None = None) -> tuple[np.ndarray, float]:
    """The diverging image of a signed (H, W) difference over ±span (None: auto_span), white at 0,
    with its scale bar below; returns (image, span)."""
    span = auto_span(difference) if span is None else float(span)
    check_range(-span, span)
    image = palette.diverging_image(difference, span)
    return legend.below(image, legend.diverging_bar(difference.shape[1], span)), span


def summary(values: np.ndarray) -> dict:
    """Mean, median, 90th/99th percentiles and max of a counter or difference plane."""
    v = np.asarray(values, np.float64).ravel()
    if not v.size:
        return {}
    p50, p90, p99 = np.percentile(v, [50, 90, 99])
    return {
        "mean": float(v.mean()),
        "median": float(p50),
        "p90": float(p90),
        "p99": float(p99),
        "min": float(v.min()),
        "max": float(v.max()),
    }
