"""The measurement protocol of `bvhlab compare`: how many samples, what is reported, and when a
claim gets a verdict.

- Every method is measured in interleaved rounds (one frame, or one build, of each method per
  round, the order rotated each round), after one warm-up round that is not counted: the load of a
  shared machine then falls on every method alike.
- A figure is reported as the median of its samples and its spread, the distribution-free
  confidence interval of that median from order statistics (`median_interval`, at least 90%; for 5
  samples it is min–max, for 9 the 2nd–8th smallest). Fewer than 5 samples give no interval.
- A claim compares two methods through the ratios of their samples taken in the same round
  (paired, so slow drifts of the machine's load cancel), with the interval of the median ratio.
  The verdict is "holds" or "does NOT hold" only when that whole interval lies on one side of the
  claim's threshold, the difference exceeding the spread; otherwise it is "inconclusive".
"""

from __future__ import annotations

import math
import statistics
from collections.abc import Iterator
from dataclasses import dataclass

from .. import _checks

MIN_SAMPLES = 5
#: Frames per method by default: 15 leave out up to 3 stalled rounds on each side of the interval.
DEFAULT_FRAMES = 15
#: Builds per method by default: builds are cheap, and 31 narrow the interval to [x_10, x_22].
DEFAULT_BUILDS = 31
#: Frames or builds per method at most (issue 39.3: --frames 1e23 ran until memory ran out). The
#: interval of a median narrows as 1/√n: beyond 10,000 samples it is far below the drift of a
#: shared machine's load, and 10,000 frames of each of five methods already take hours.
MAX_SAMPLES = 10_000
CONFIDENCE = 0.90
HOLDS, FAILS, INCONCLUSIVE = "holds", "does NOT hold", "inconclusive"


@dataclass(frozen=True)
class Interval:
    """A median and the interval that contains the true median with probability >= CONFIDENCE
    (lo = hi = nan when there are too few samples for one)."""

    median: float
    lo: float
    hi: float
    n: int

    @property
    def known(self) -> bool:
        return not math.isnan(self.lo)

    def text(self, digits: int = 1) -> str:
        if not self.known:
            return f"{self.median:.{digits}f} (n={self.n}, too few for a spread)"
        return f"{self.median:.{digits}f} [{self.lo:.{digits}f}–{self.hi:.{digits}f}]"


def _order_rank(n: int, confidence: float = CONFIDENCE) -> int | None:
    """The largest k such that [x_(k), x_(n+1-k)] (1-based order statistics) covers the median
    with probability >= confidence: 1 - 2·P(Binomial(n, 1/2) <= k - 1). The binomial coefficient
    is carried from one k to the next, exactly (a fresh math.comb each step took 15 s at n = 10,000)."""
    best, below, ways, total = None, 0.0, 1, 2**n  # ways = comb(n, k - 1)
    for k in range(1, n // 2 + 1):
        below += ways / total
        if 1 - 2 * below >= confidence:
            best = k
        else:
            break
        ways = ways * (n - k + 1) // k
    return best


def median_interval(samples) -> Interval:
    values = sorted(float(x) for x in samples)
    if not values:
        raise ValueError("no samples")
    k = _order_rank(len(values)) if len(values) >= MIN_SAMPLES else None
    if k is None:
        return Interval(statistics.median(values), math.nan, math.nan, len(values))
    return Interval(statistics.median(values), values[k - 1], values[-k], len(values))


def paired(function, *series) -> Interval:
    """Median of function(a_i, b_i, ...) over rounds i (samples of one round taken together), with
    its interval."""
    if len({len(s) for s in series}) != 1:
        raise ValueError(f"paired samples differ in count ({', '.join(str(len(s)) for s in series)})")
    return median_interval([function(*values) for values in zip(*series)])


def paired_ratio(a, b) -> Interval:
    """Median of a_i / b_i over rounds i, with its interval. A round whose b_i is 0 (a frame too
    short for the clock) has no ratio and is left out, so the interval widens or becomes unknown
    rather than a division failing; with no round left the median is unknown too (nan)."""
    if len(a) != len(b):
        raise ValueError(f"paired samples differ in count ({len(a)}, {len(b)})")
    ratios = [x / y for x, y in zip(a, b) if y > 0]
    if not ratios:
        return Interval(math.nan, math.nan, math.nan, 0)
    return median_interval(ratios)


def at_most(ratio: Interval, limit: float) -> str:
    """Verdict on "ratio <= limit"."""
    if not ratio.known:
        return INCONCLUSIVE
    return HOLDS if ratio.hi <= limit else FAILS if ratio.lo > limit else INCONCLUSIVE


def at_least(ratio: Interval, limit: float) -> str:
    """Verdict on "ratio >= limit"."""
    if not ratio.known:
        return INCONCLUSIVE
    return HOLDS if ratio.lo >= limit else FAILS if ratio.hi < limit else INCONCLUSIVE


def within(ratio: Interval, tolerance: float) -> str:
    """Verdict on "1 - tolerance <= ratio <= 1 + tolerance" (the two differ little)."""
    if not ratio.known:
        return INCONCLUSIVE
    lo, hi = 1 - tolerance, 1 + tolerance
    if lo <= ratio.lo and ratio.hi <= hi:
        return HOLDS
    return FAILS if ratio.hi < lo or ratio.lo > hi else INCONCLUSIVE


def all_of(verdicts: list[str]) -> str:
    """Verdict on a conjunction: fails if one part fails, holds if all hold."""
    if FAILS in verdicts:
        return FAILS
    return HOLDS if verdicts and all(v == HOLDS for v in verdicts) else INCONCLUSIVE


def rounds(labels: list[str], count: int) -> Iterator[list[str]]:
    """`count` rounds over `labels`, each starting one label later than the one before, so no
    label is always first after a pause (or always right after the same other label). Made one at
    a time, as they are measured: nothing is held for rounds still to come."""
    n = len(labels)
    for r in range(count):
        yield [labels[(r + i) % n] for i in range(n)]


def sample_count(name: str, value) -> int:
    """A number of frames or builds per method: a whole number from 1 to MAX_SAMPLES (the protocol's
    interval needs MIN_SAMPLES; fewer give a median without one)."""
    return _checks.integer(name, value, 1, MAX_SAMPLES)
