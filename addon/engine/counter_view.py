"""The Rendered viewport's counter display (issue 35): a traversal counter per pixel on the core's
heat ramp instead of the shaded image, over a manual range or the auto range
(bvhlab.counters.auto_range: 0 to the 99th percentile of the frame). No bpy: the settings are read
into a CounterView on the UI thread, the image is made on the viewport's worker."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: The display that shows the shaded image (the render mode's), not a counter.
NO_COUNTER = "none"


@dataclass(frozen=True)
class CounterView:
    """Which counter the viewport shows, and over which range (None: auto)."""

    counter: str
    value_range: tuple[float, float] | None


def counter_view(settings) -> CounterView | None:
    """The CounterView of the scene's settings (scene.bvhlab), None for the shaded display."""
    if settings.viewport_counter == NO_COUNTER:
        return None
    manual = None if settings.counter_range_auto else (settings.counter_range_min, settings.counter_range_max)
    return CounterView(settings.viewport_counter, manual)


#: Bins of the histogram the sidebar shows (one row each).
SIDEBAR_BINS = 12


def manual_range(view: CounterView) -> tuple[float, float] | None:
    """The view's manual range (min ≥ max widened to min + 1), None for the auto range."""
    if view.value_range is None:
        return None
    lo, hi = view.value_range
    return float(lo), float(max(hi, lo + 1.0))


def shown_range(values: np.ndarray, view: CounterView) -> tuple[float, float]:
    """The range the view colours `values` over: the auto range, or the manual one."""
    from bvhlab import counters

    lo, hi = manual_range(view) or counters.auto_range(values)
    return float(lo), float(hi)


def counter_colors(all_counters: np.ndarray, view: CounterView) -> tuple[np.ndarray, tuple[float, float]]:
    """(H, W, 4) heat colours of the view's counter (no scale bar: the panel shows the legend) and
    the range used (shown_range)."""
    from bvhlab import counters, palette

    values = counters.counter_plane(all_counters, view.counter)
    lo, hi = shown_range(values, view)
    return palette.heat_image(values, lo, hi), (lo, hi)


def counter_histogram(all_counters: np.ndarray, view: CounterView):
    """The histogram (bvhlab.histogram, SIDEBAR_BINS bins) of the view's counter over the range
    counter_colors colours it with: what the sidebar shows under the counter."""
    from bvhlab import counters, histogram

    values = counters.counter_plane(all_counters, view.counter)
    return histogram.counter_histogram(values, view.counter, manual_range(view), bins=SIDEBAR_BINS)
