"""The grid of the corners that can block an ear, for the ear clipping of large polygons in
bvhlab.library.polygons (Eberly, "Triangulation by Ear Clipping", 2002, §2: only the corners
that are not strictly convex can lie in an ear), and the turn tests both modules share: exact in
sign (Shewchuk, "Adaptive Precision Floating-Point Arithmetic and Fast Robust Geometric
Predicates", 1997: the double product, and the exact one where it is within its error bound).
With the doubles' sign alone, a simple outline of corners near one line was clipped into
overlapping and flipped slivers (7 of 400 such polygons: a review), and a corner a rounding
outside an ear's box could test inside it."""

from __future__ import annotations

import bisect
from collections.abc import Sequence

import numpy as np

#: Shewchuk's ccwerrboundA, (3 + 16ε)ε with ε = 2^-53: past it, the sign of the double
#: expression is that of the exact one (the subtractions' roundings included).
_BOUND = (3.0 + 16.0 * 2.0**-53) * 2.0**-53


def _exact(o, a, b) -> float:
    """The sign (-1.0, 0.0 or 1.0) of (a − o) × (b − o) in exact arithmetic: each double an integer
    over a power of two, all brought to the largest denominator (integers; fractions.Fraction took
    12 µs a test against 2, which outlines of many collinear corners call for most corners); 0.0
    where a coordinate is not finite (no sign to give: such corners are refused by the readers)."""
    try:
        ratios = [float(v).as_integer_ratio() for v in (o[0], o[1], a[0], a[1], b[0], b[1])]
    except (OverflowError, ValueError):
        return 0.0
    den = max(q for _, q in ratios)
    ox, oy, ax, ay, bx, by = (p * (den // q) for p, q in ratios)
    det = (ax - ox) * (by - oy) - (ay - oy) * (bx - ox)
    return float((det > 0) - (det < 0))


def turn1(o: Sequence[float], a: Sequence[float], b: Sequence[float]) -> float:
    """(a − o) × (b − o) of one corner in Python floats, of the exact sign: > 0 where o, a, b turn
    left, 0 where they are collinear (the value itself only where its sign is certain)."""
    left = (a[0] - o[0]) * (b[1] - o[1])
    right = (a[1] - o[1]) * (b[0] - o[0])
    det = left - right
    if abs(det) > _BOUND * (abs(left) + abs(right)):  # false for NaN
        return det
    return _exact(o, a, b)


def inside(pa, pb, pc, q) -> bool:
    """Whether q lies in the closed triangle pa, pb, pc (counter-clockwise) and is none of its
    corners: a corner at one of an ear's own (a polygon bridged to its hole, a "keyhole", repeats
    them) does not block it."""
    if turn1(pa, pb, q) >= 0 and turn1(pb, pc, q) >= 0 and turn1(pc, pa, q) >= 0:
        return not any(q[0] == r[0] and q[1] == r[1] for r in (pa, pb, pc))
    return False


class Blockers:
    """The corners that can block an ear (blocking ones) on a uniform grid over the polygon's
    bounds, about four cells a blocking corner and as square as the bounds allow, each row's
    corners sorted by cell: the corners whose cell meets an ear's bounding box are all that can lie
    in the ear (the turn tests are exact: no corner outside the box tests inside the triangle). A
    cell is a monotone function of a point, so a point inside a box has its cell within the box's
    corners' cells: the test's answers are those of a test of every corner. A corner that stops
    blocking leaves its row; one that starts (a degenerate or self-intersecting outline: clipping
    ears turns corners convex, never reflex, in a simple polygon, Eberly §2) joins it."""

    def __init__(self, xy: np.ndarray, blocking: np.ndarray):
        self.points = xy
        #: the corners as Python floats: an ear's own test in scalars (turn1)
        self.xy = [(float(x), float(y)) for x, y in xy]
        #: which corners block, as a list (scalar reads) and an array (numpy's)
        self.mask, self.blocks = blocking.copy(), blocking.tolist()
        self.count = int(blocking.sum())
        #: the ear tests' work so far: corners read and grid rows looked at (_ear_clip's budget)
        self.reads = 0
        with np.errstate(over="ignore", invalid="ignore"):
            span = xy.max(axis=0) - xy.min(axis=0)
        # one cell where the bounds are not finite (corners near ±1e308: the reader refuses them
        # after; a grid of them raised "cannot convert float NaN to integer" first)
        self.lo, self.size, self.shape = [0.0, 0.0], [1.0, 1.0], [1, 1]
        cells = 4 * self.count  # a corner to about four cells
        if np.isfinite(span).all() and self.count > 1:
            w, h = (float(v) for v in span)
            side = max(np.sqrt(w * h / cells), w / cells, h / cells)
            self.shape = [min(max(int(v / side), 1), cells) if side > 0 else 1 for v in (w, h)]
            self.lo = [float(v) for v in xy.min(axis=0)]
            self.size = [v / k if v > 0 else 1.0 for v, k in zip((w, h), self.shape, strict=True)]
        #: each row's blocking corners, as x cell × n + corner, sorted: a box's are a slice a row
        self.rows: list[list[int]] = [[] for _ in range(self.shape[1])]
        for v in np.flatnonzero(blocking).tolist():
            self.rows[self._cell(self.xy[v][1], 1)].append(self._code(v))
        for row in self.rows:
            row.sort()

    def _cell(self, x: float, axis: int) -> int:
        """The cell of coordinate x along axis."""
        k = self.shape[axis]
        return 0 if k == 1 else min(max(int((x - self.lo[axis]) / self.size[axis]), 0), k - 1)

    def _code(self, v: int) -> int:
        return self._cell(self.xy[v][0], 0) * len(self.xy) + v

    def include(self, v: int, blocks: bool) -> None:
        """Corner v blocks (`blocks`) or not since a neighbour was clipped."""
        if not blocks:
            self.exclude(v)
        elif not self.blocks[v]:
            self.blocks[v] = self.mask[v] = True
            bisect.insort(self.rows[self._cell(self.xy[v][1], 1)], self._code(v))
            self.count += 1

    def exclude(self, v: int) -> None:
        """Corner v is clipped or turned convex: off the grid."""
        if self.blocks[v]:
            self.blocks[v] = self.mask[v] = False
            row = self.rows[self._cell(self.xy[v][1], 1)]
            del row[bisect.bisect_left(row, self._code(v))]
            self.count -= 1

    def near(self, x0: float, y0: float, x1: float, y1: float) -> list[int]:
        """The corners on the grid whose cells meet the box [x0, x1] × [y0, y1] (with the doubles'
        sign, a corner 2^-53 off an ear's box tested inside it, and a cell more on every side
        was read: ~5 times the time on a 160,000-corner star; exact tests need none)."""
        n = len(self.xy)
        lo, hi = self._cell(x0, 0) * n, (self._cell(x1, 0) + 1) * n
        out: list[int] = []
        rows = self.rows[self._cell(y0, 1) : self._cell(y1, 1) + 1]
        for row in rows:
            if row:
                out += row[bisect.bisect_left(row, lo) : bisect.bisect_left(row, hi)]
        self.reads += len(rows)
        return [code % n for code in out]

    def is_ear(self, a: int, b: int, c: int) -> bool:
        """Whether corner b (between a and c) is an ear: convex, and no other corner that can
        block lies in the closed triangle abc. A corner at one of the ear's own corners (a
        polygon bridged to its hole, a "keyhole", repeats them) does not block: it fanned over
        the hole."""
        pa, pb, pc = self.xy[a], self.xy[b], self.xy[c]
        (ax, ay), (bx, by), (cx, cy) = pa, pb, pc
        if turn1(pa, pb, pc) <= 0:
            return False  # a reflex or flat corner is no ear
        if not self.count:
            return True
        others = self.near(min(ax, bx, cx), min(ay, by, cy), max(ax, bx, cx), max(ay, by, cy))
        self.reads += len(others)
        if len(others) > 64:  # in numpy
            idx = np.array(others, np.int64)
            idx = idx[self.mask[idx] & (idx != a) & (idx != b) & (idx != c)]
            p = self.points[idx]
            qa, qb, qc = self.points[a], self.points[b], self.points[c]
            within = (turn(qa, qb, p) >= 0) & (turn(qb, qc, p) >= 0) & (turn(qc, qa, p) >= 0)
            at_corner = np.zeros(len(p), bool)
            for q in (qa, qb, qc):
                at_corner |= (p[:, 0] == q[0]) & (p[:, 1] == q[1])
            return not np.any(within & ~at_corner)
        xy, blocks = self.xy, self.blocks
        return not any(inside(pa, pb, pc, xy[v]) for v in others if blocks[v] and v != a and v != b and v != c)


def turn(o: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """turn1 row by row, in numpy: the double products, and the exact sign where they are within
    their error bound (or not finite)."""
    left = (a[..., 0] - o[..., 0]) * (b[..., 1] - o[..., 1])
    right = (a[..., 1] - o[..., 1]) * (b[..., 0] - o[..., 0])
    with np.errstate(invalid="ignore", over="ignore"):
        det = left - right
        unsure = ~(np.abs(det) > _BOUND * (np.abs(left) + np.abs(right)))
    if unsure.any():
        o, a, b = (np.broadcast_to(x, det.shape + (2,)) for x in (o, a, b))
        for i in zip(*np.nonzero(unsure)):
            det[i] = _exact(o[i].tolist(), a[i].tolist(), b[i].tolist())
    return det
