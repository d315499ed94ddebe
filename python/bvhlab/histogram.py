"""The histogram of a traversal counter over a render's pixels (issue 35; the histogram of AMD's
Radeon Raytracing Analyzer's traversal-counter view): how many pixels needed how many box tests,
box hits, primitive tests, primitive hits or instance hits per primary ray.

The bins span the counter's colour range (a manual range, or the auto range of bvhlab.counters:
0 to the 99th percentile), so the histogram is of what the image shows: a pixel outside the range
is counted in the end bin its colour saturates to (`below` and `above` say how many), and the
counts always add up to the pixel count. Whole-number counts (one sample per pixel) get bins of
whole numbers, each holding the same number of integers, and averages over n × n samples bins of
the same number of multiples of 1/n²; other values get even bins.
Each bar is drawn in the heat colour of its bin's middle (bvhlab.palette), so the strip is the
image's legend too. The percentiles and the maximum are of the values themselves."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from . import _core, counters, legend, palette

#: Bins of a histogram at most (the CLI's); the sidebar shows fewer (SIDEBAR_BINS in the add-on).
DEFAULT_BINS = 32
#: The percentiles reported beside the maximum.
PERCENTILES = (50, 90, 99)
#: Height of the bars' area of the strip (pixels), and the narrowest bar.
PLOT_HEIGHT = 64
MIN_BAR_WIDTH = 3


@dataclass(frozen=True)
class CounterHistogram:
    """Pixel counts of a counter plane per bin: bin k holds values in [edges[k], edges[k + 1]) (the
    last also its right end), the end bins also every value below / above `value_range`."""

    counter: str
    edges: np.ndarray  # (bins + 1,) float64, increasing
    counts: np.ndarray  # (bins,) int64
    value_range: tuple[float, float]  # the colour range the bins span
    auto: bool  # value_range is the auto range
    grid: int | None  # the values are whole multiples of 1/grid (value_grid), or None
    below: int  # pixels below value_range[0] (in bin 0)
    above: int  # pixels above value_range[1] (in the last bin)
    mean: float
    percentiles: dict  # "p50", "p90", "p99", "max" of the values

    @property
    def pixels(self) -> int:
        return int(self.counts.sum())

    @property
    def middles(self) -> np.ndarray:
        return (self.edges[:-1] + self.edges[1:]) / 2

    def bin_labels(self) -> list[str]:
        """A short label per bin: the grid values it holds ('3', '4-7', '1.25-1.5'), or its edges
        ('0.5-1.2'); '+' after the last where pixels above the range are in it, '≤ ' before the
        first where pixels below it are in that."""
        labels = []
        for a, b in zip(self.edges[:-1], self.edges[1:]):
            if self.grid is None:
                first, last = float(a), float(b)
            else:
                q = self.grid
                first, last = math.ceil(a * q) / q, math.floor(b * q) / q
            text = legend.number_text(first) if first == last else f"{_short(first)}-{_short(last)}"
            labels.append(text)
        if self.above:
            labels[-1] += "+"
        if self.below:
            labels[0] = "≤ " + labels[0]
        return labels

    def colors(self) -> np.ndarray:
        """(bins, 3) heat colour of each bin's middle over the colour range (the image's colours)."""
        lo, hi = self.value_range
        return palette.heat(palette.scaled(np.clip(self.middles, lo, hi), lo, hi))

    def to_json(self) -> dict:
        return {
            "counter": self.counter,
            "range": list(self.value_range),
            "auto_range": self.auto,
            "auto_percentile": counters.AUTO_PERCENTILE,
            "bins": [[float(a), float(b)] for a, b in zip(self.edges[:-1], self.edges[1:])],
            "counts": [int(c) for c in self.counts],
            "pixels": self.pixels,
            "below_range": self.below,
            "above_range": self.above,
            "mean": self.mean,
            "percentiles": self.percentiles,
        }


#: The sample counts a pixel's average can be over (n × n samples, n up to the core's most).
_SAMPLE_COUNTS = tuple(n * n for n in range(1, int(_core.MAX_SAMPLES_PER_AXIS) + 1))


def _distinct(values) -> tuple[np.ndarray, np.ndarray]:
    """The sorted distinct values (in their own dtype) and how many pixels hold each. A counter plane
    has few distinct values: after this one sort the grid, the bins and the percentiles cost next to
    nothing (a 1920 × 1080 plane's histogram is about one np.unique)."""
    distinct, counts = np.unique(np.asarray(values).ravel(), return_counts=True)
    return distinct, counts.astype(np.int64)


#: How far from a whole number q·value may be and still be k / q: float32 averages of q samples
#: (34/9 in float32, times 9, is 33.9999990)
_GRID_SLACK = 1e-3


def _grid_of(distinct: np.ndarray) -> int | None:
    def on(d: np.ndarray, q: int) -> bool:
        scaled = d * q
        return bool(np.all(np.abs(scaled - np.round(scaled)) < _GRID_SLACK))

    d = np.asarray(distinct, np.float64)
    few = d[:: max(len(d) // 64, 1)]  # a sample first: values off every grid fail fast
    return next((q for q in _SAMPLE_COUNTS if on(few, q) and on(d, q)), None)


def value_grid(values: np.ndarray) -> int | None:
    """The smallest sample count q for which every value is a whole number of 1/q (counts averaged
    over q samples; 1 for whole numbers), None when there is none."""
    return _grid_of(_distinct(values)[0])


def percentile(distinct: np.ndarray, counts: np.ndarray, q: float) -> float:
    """np.percentile(values, q) (numpy's default, linear method; the same float) of the values
    given as their sorted distinct values and counts."""
    n = int(counts.sum())
    index = q / 100 * (n - 1)
    below = math.floor(index)
    ends = np.cumsum(counts)
    a = distinct[np.searchsorted(ends, below, side="right")]
    b = distinct[np.searchsorted(ends, min(below + 1, n - 1), side="right")]
    t = np.float64(index - below)
    step = b - a
    return float(a + step * t) if t < 0.5 else float(b - step * (1 - t))  # numpy's _lerp


def _short(value: float) -> str:
    return legend.number_text(round(value, 3))


def bin_edges(values: np.ndarray, lo: float, hi: float, most: int = DEFAULT_BINS) -> np.ndarray:
    """Edges of at most `most` bins over lo..hi. Values on a grid of 1/q (value_grid: averages of
    whole counts over q samples) get bins of the same number of grid points each, edges half-way
    between them (no bin holds one point more than its neighbour); other values `most` even bins."""
    return _edges(value_grid(values) if np.size(values) else None, lo, hi, most)


def _edges(q: int | None, lo: float, hi: float, most: int) -> np.ndarray:
    if most < 1:
        raise ValueError(f"a histogram needs at least one bin, got {most}")
    if q is not None and _on_grid(q, lo, hi):
        first, last = _grid_span(q, lo, hi)
        points = last - first + 1
        width = -(-points // most)
        bins = -(-points // width)
        return (first - 0.5 + width * np.arange(bins + 1, dtype=np.float64)) / q
    return np.linspace(lo, hi, most + 1, dtype=np.float64)


def _grid_span(q: int, lo: float, hi: float) -> tuple[int, int]:
    """The first and last k of the grid points k / q in lo..hi, the ends as _grid_of reads values
    (within _GRID_SLACK): a range's top of float32(34/9) is 34/9, whose bin held 3.7778 nowhere
    (probe: 3×3 samples, the top value's pixels above every bin)."""
    return math.ceil(lo * q - _GRID_SLACK), math.floor(hi * q + _GRID_SLACK)


def _on_grid(q: int | None, lo: float, hi: float) -> bool:
    """Whether lo..hi holds a point of the grid 1/q (grid bins need one)."""
    if q is None:
        return False
    first, last = _grid_span(q, lo, hi)
    return last >= first


def counter_histogram(
    values: np.ndarray, counter: str, value_range: tuple[float, float] | None = None, bins: int = DEFAULT_BINS
) -> CounterHistogram:
    """The histogram of an (H, W) plane of `counter` over `value_range` (None: the auto range, as
    counters.counter_image colours it)."""
    counters.counter_index(counter)  # an unknown name: ValueError
    distinct, counts = _distinct(values)
    if not np.isfinite(distinct).all():
        raise ValueError("counter values must be finite")
    if value_range is None:  # counters.auto_range, from the distinct values
        top = percentile(distinct, counts, counters.AUTO_PERCENTILE) if distinct.size else 0.0
        lo, hi = counters.range_to(top)
    else:
        lo, hi = float(value_range[0]), float(value_range[1])
    counters.check_range(lo, hi)
    grid = _grid_of(distinct) if distinct.size else None
    edges = _edges(grid, lo, hi, bins)
    # bin k: edges[k] <= v < edges[k + 1]; outside the edges: the end bins (the image saturates)
    index = np.clip(np.searchsorted(edges, distinct, side="right") - 1, 0, len(edges) - 2)
    binned = np.bincount(index, weights=counts, minlength=len(edges) - 1)
    if distinct.size:
        percentiles = {f"p{q}": percentile(distinct, counts, q) for q in PERCENTILES}
        percentiles["max"] = float(distinct[-1])
        mean = float(np.dot(distinct.astype(np.float64), counts) / counts.sum())
    else:
        percentiles, mean = {f"p{q}": 0.0 for q in PERCENTILES} | {"max": 0.0}, 0.0
    return CounterHistogram(
        counter=counter,
        edges=edges,
        counts=np.round(binned).astype(np.int64),
        value_range=(lo, hi),
        auto=value_range is None,
        grid=grid if _on_grid(grid, lo, hi) else None,
        below=int(counts[distinct < lo].sum()),
        above=int(counts[distinct > hi].sum()),
        mean=mean,
        percentiles=percentiles,
    )


def strip_width(histogram: CounterHistogram, width: int) -> int:
    """The strip's width: `width` (the image's), widened until every bar is MIN_BAR_WIDTH wide."""
    return max(int(width), 2 * legend.MARGIN + MIN_BAR_WIDTH * len(histogram.counts))


def bar_columns(histogram: CounterHistogram, width: int) -> np.ndarray:
    """(bins + 1,) the first column of each bar in a strip `width` wide (and the end of the last)."""
    inner = width - 2 * legend.MARGIN
    n = len(histogram.counts)
    return legend.MARGIN + (np.arange(n + 1) * inner) // n


def bar_heights(histogram: CounterHistogram) -> np.ndarray:
    """(bins,) each bar's height in pixels: the tallest PLOT_HEIGHT, any non-empty bin at least 1."""
    tallest = max(int(histogram.counts.max(initial=0)), 1)
    h = np.round(histogram.counts / tallest * PLOT_HEIGHT).astype(int)
    return np.where(histogram.counts > 0, np.maximum(h, 1), 0)


#: Rows of the strip: the tallest count's number, the bars, the range's numbers.
PLOT_TOP = legend.MARGIN + legend.TEXT_HEIGHT + legend.MARGIN


def histogram_strip(histogram: CounterHistogram, width: int) -> np.ndarray:
    """(h, strip_width(width), 4) linear RGBA: the bars (bottom-aligned, each in its bin's heat
    colour), the tallest bar's pixel count above them at the left, and the numbers of the colour
    range's ends below them."""
    width = strip_width(histogram, width)
    bottom = PLOT_TOP + PLOT_HEIGHT
    strip = legend.blank_strip(bottom + legend.MARGIN + legend.TEXT_HEIGHT + legend.MARGIN, width)
    columns, heights = bar_columns(histogram, width), bar_heights(histogram)
    for k, rgb in enumerate(histogram.colors()):
        strip[bottom - heights[k] : bottom, columns[k] : columns[k + 1], :3] = rgb
    legend.draw_text(strip, legend.number_text(int(histogram.counts.max(initial=0))), legend.MARGIN, legend.MARGIN)
    y = bottom + legend.MARGIN
    lo, hi = histogram.value_range
    legend.draw_text(strip, legend.number_text(lo), legend.MARGIN, y)
    hi_text = legend.number_text(hi)
    legend.draw_text(strip, hi_text, width - legend.MARGIN - legend.text_mask(hi_text).shape[1], y)
    return strip
