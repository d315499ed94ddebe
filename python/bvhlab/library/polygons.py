"""Polygons of mesh files into triangles: a fan where the polygon is convex (its corners all turn
the same way about its normal), ear clipping where it is not (Eberly, "Triangulation by Ear
Clipping", 2002) — a fan over a concave polygon covers space outside it (a concave pentagon of
area 2.5 became triangles of area 3.5). Both give n − 2 triangles of the polygon's own corners.
Polygons of at most _SMALL corners are clipped along Eberly's walk (_ear_clip_small: the next ear
along the outline); larger ones smallest ear first (_ear_clip), whose triangles differ from the
walk's: the walk was quadratic on spiky outlines (a 160,000-corner star: 21 s, ~6 s since; a
160,000-corner comb of long teeth: minutes, ~1.3 s)."""

from __future__ import annotations

import bisect
import heapq
from collections.abc import Sequence

import numpy as np


def triangulate(corners, positions: np.ndarray) -> list[tuple[int, int, int]]:
    """Triangles (vertex indices) covering the polygon whose vertices are `corners` (indices into
    `positions`, float (V, 3)), in the polygon's winding. Degenerate polygons (collinear, repeated
    or self-intersecting corners, where no ear is found) fall back to a fan."""
    corners = list(corners)
    n = len(corners)
    if n == 3:
        return [(corners[0], corners[1], corners[2])]
    p = positions[corners]
    normal = _newell_normals(p[None])[0]
    turns = _turns(p[None], normal[None])[0]  # < 0 where convex
    if not (turns > 0).any() or not np.any(normal):  # convex, or no area to clip ears from
        return _fan(corners)
    xy = _projected(p, normal)
    if n <= _SMALL:  # the triangles of triangulate_all's clipping of small polygons
        return _ear_clip_small(corners, xy.astype(np.float64).tolist()) or _fan(corners)
    return _ear_clip(corners, xy) or _fan(corners)


def triangulate_all(polygons: Sequence[Sequence[int] | np.ndarray], positions: np.ndarray) -> np.ndarray:
    """int64 (T, 3): `triangulate` of every polygon, triangles and quads in numpy at once (a mesh
    file's millions of faces), in the polygons' order by size (3, 4, then larger ones)."""
    by_size: dict[int, list[Sequence[int] | np.ndarray]] = {}
    for corners in polygons:
        if len(corners) >= 3:
            by_size.setdefault(len(corners), []).append(corners)
    out = [np.zeros((0, 3), np.int64)]
    for size in sorted(by_size):
        out.append(_of_size(size, np.array(by_size[size], np.int64), positions))
    return np.concatenate(out)


def triangulate_runs(corners: np.ndarray, sizes: np.ndarray, positions: np.ndarray) -> np.ndarray:
    """triangulate_all of polygons laid end to end: polygon k is the sizes[k] corners of `corners`
    (int64) after those of the polygons before it; those of fewer than 3 corners (a file's points
    and edges) make no triangles. The same triangles in the same order, without a Python object
    for each polygon (an OBJ of 490,000 quads peaked at 710 MiB through triangulate_all)."""
    starts = np.cumsum(sizes) - sizes
    out = [np.zeros((0, 3), np.int64)]
    for size in np.unique(sizes[sizes >= 3]).tolist():  # ascending
        first = starts[sizes == size]
        out.append(_of_size(size, corners[first[:, None] + np.arange(size)], positions))
    return np.concatenate(out)


def _of_size(size: int, faces: np.ndarray, positions: np.ndarray) -> np.ndarray:
    """int64 (T, 3): the triangles of polygons of `size` corners, faces (F, size), in their order;
    _BLOCK faces at a time, which bounds the temporaries of the arithmetic on their corners (the
    same operations on each face: the same triangles)."""
    if size == 3:
        return faces
    split = _quads if size == 4 else _larger
    return np.concatenate(
        [np.zeros((0, 3), np.int64)] + [split(faces[k : k + _BLOCK], positions) for k in range(0, len(faces), _BLOCK)]
    )


#: Faces _of_size hands on at a time: 490,000 quads at once held ~330 MiB of corner arithmetic.
_BLOCK = 1 << 16


def _larger(faces: np.ndarray, positions: np.ndarray) -> np.ndarray:
    """`triangulate` of polygons of one size n > 4 (F, n): the convex ones' fans in numpy at once,
    the others one by one (a 200,000-hexagon OBJ: 23.7 s, ~120 µs a polygon in `triangulate`: a
    helper's probe). The same test as triangulate's, face by face: the same triangles."""
    p = positions[faces]  # (F, n, 3)
    normal = _newell_normals(p)
    turns = _turns(p, normal)
    fan = ~(turns > 0).any(axis=1) | ~normal.any(axis=1)
    n = faces.shape[1]
    k = np.arange(1, n - 1)
    out = np.stack([np.repeat(faces[:, :1], n - 2, axis=1), faces[:, k], faces[:, k + 1]], axis=2)  # (F, n-2, 3)
    clipped = np.flatnonzero(~fan)
    if n > _SMALL:
        for f in clipped:
            out[f] = triangulate(faces[f].tolist(), positions)
        return out.reshape(-1, 3)
    # as floats whatever the positions' type, as _ear_clip's (integers were exact: the review's)
    xy = _projected_all(p[clipped], normal[clipped]).astype(np.float64)
    for f, corners, points in zip(clipped.tolist(), faces[clipped].tolist(), xy.tolist(), strict=True):
        out[f] = _ear_clip_small(corners, points) or _fan(corners)
    return out.reshape(-1, 3)


#: Polygons of at most this many corners are ear-clipped by _ear_clip_small (Python floats, every
#: blocking corner tested: O(n²)); larger ones by _ear_clip (numpy, a grid of the blockers).
_SMALL = 32


def _ear_clip_small(corners: list[int], xy: list[list[float]]) -> list[tuple[int, int, int]] | None:
    """Ear clipping of a small polygon in Python floats along Eberly's walk (the next ear from the
    last one clipped), the clipping of every polygon of at most _SMALL corners, by triangulate and
    triangulate_all alike (the same triangles; the blocking corners' test by _Blockers.is_ear's IEEE
    double operations), without numpy's cost on a handful of corners (~300 µs a concave hexagon:
    150,000 of them took 49 s in an OBJ, a helper's probe)."""
    n = len(corners)
    nxt, prv = [*range(1, n), 0], [n - 1, *range(n - 1)]

    def turn(o: list[float], a: list[float], b: list[float]) -> float:  # _turn's operations
        return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])

    def is_ear(a: int, b: int, c: int) -> bool:  # _Blockers.is_ear over every blocking corner
        pa, pb, pc = xy[a], xy[b], xy[c]
        if turn(pa, pb, pc) <= 0:
            return False
        for v in range(n):
            if not blocking[v] or v == a or v == b or v == c:
                continue
            q = xy[v]
            if turn(pa, pb, q) >= 0 and turn(pb, pc, q) >= 0 and turn(pc, pa, q) >= 0:
                if not any(q[0] == r[0] and q[1] == r[1] for r in (pa, pb, pc)):
                    return False
        return True

    alive = [True] * n
    blocking = [turn(xy[prv[v]], xy[v], xy[nxt[v]]) <= 0 for v in range(n)]
    ear = [is_ear(prv[b], b, nxt[b]) for b in range(n)]
    out = []
    b, left = 0, n
    while left > 3:
        # the walk: the next ear from b on, else the first
        found = next((k for k in [*range(b, n), *range(b)] if ear[k] and alive[k]), None)
        if found is None:
            return None
        b = found
        a, c = prv[b], nxt[b]
        out.append((corners[a], corners[b], corners[c]))
        alive[b] = blocking[b] = ear[b] = False
        nxt[a], prv[c] = c, a
        left -= 1
        for v in (a, c):
            blocking[v] = turn(xy[prv[v]], xy[v], xy[nxt[v]]) <= 0
        for v in (a, c):
            ear[v] = is_ear(prv[v], v, nxt[v])
        b = c
    a = alive.index(True)
    out.append((corners[a], corners[nxt[a]], corners[nxt[nxt[a]]]))
    return out


def _quads(faces: np.ndarray, positions: np.ndarray) -> np.ndarray:
    """Two triangles per quad (a, b, c, d): across a–c, or across b–d where b or d is a reflex
    corner (a simple quad has at most one; a–c would leave the quad there)."""
    p = positions[faces]  # (F, 4, 3)
    normal = np.cross(p[:, 2] - p[:, 0], p[:, 3] - p[:, 1])  # Newell's normal of a quad
    turns = np.einsum("fkc,fc->fk", np.cross(np.roll(p, 1, axis=1) - p, np.roll(p, -1, axis=1) - p), normal)
    other = (turns[:, 1] > 0) | (turns[:, 3] > 0)
    a, b, c, d = faces.T
    first = np.where(other[:, None], np.stack([b, c, d], 1), np.stack([a, b, c], 1))
    second = np.where(other[:, None], np.stack([b, d, a], 1), np.stack([a, c, d], 1))
    return np.stack([first, second], 1).reshape(-1, 3)


def _turns(p: np.ndarray, normal: np.ndarray) -> np.ndarray:
    """(F, n): how each corner of polygons p (F, n, 3) turns about their normals (F, 3), < 0 where
    convex, by the same operations in the same order for one polygon and for many (a product by
    `@` went through BLAS, whose last bits differ from einsum's: a flat corner's sign flipped and
    one path fanned what the other clipped; the review)."""
    c = np.cross(np.roll(p, 1, axis=1) - p, np.roll(p, -1, axis=1) - p)
    return (c[..., 0] * normal[:, None, 0] + c[..., 1] * normal[:, None, 1]) + c[..., 2] * normal[:, None, 2]


def _fan(corners: list[int]) -> list[tuple[int, int, int]]:
    return [(corners[0], corners[i], corners[i + 1]) for i in range(1, len(corners) - 1)]


def _newell_normals(p: np.ndarray) -> np.ndarray:
    """(F, 3): the normals of polygons p (F, n, 3) by Newell's method (robust for non-planar and
    concave polygons), each summed as one polygon's alone (the rows are contiguous)."""
    q = np.roll(p, -1, axis=1)
    return np.stack(
        [
            np.sum((p[..., 1] - q[..., 1]) * (p[..., 2] + q[..., 2]), axis=1),
            np.sum((p[..., 2] - q[..., 2]) * (p[..., 0] + q[..., 0]), axis=1),
            np.sum((p[..., 0] - q[..., 0]) * (p[..., 1] + q[..., 1]), axis=1),
        ],
        axis=1,
    )


def _projected(p: np.ndarray, normal: np.ndarray) -> np.ndarray:
    """2D coordinates in the polygon's plane, counter-clockwise for its winding."""
    return _projected_all(p[None], normal[None])[0]


def _projected_all(p: np.ndarray, normal: np.ndarray) -> np.ndarray:
    """_projected of polygons p (F, n, 3) with normals (F, 3) at once: (F, n, 2), each dropping
    the axis its normal is largest along."""
    axis = np.argmax(np.abs(normal), axis=1)
    u, v = np.array([1, 2, 0])[axis], np.array([2, 0, 1])[axis]
    xy = np.concatenate([np.take_along_axis(p, w[:, None, None], axis=2) for w in (u, v)], axis=2)
    flip = ~(normal[np.arange(len(p)), axis] > 0)
    xy[flip] = xy[flip][..., ::-1]
    return xy


def _ear_clip(corners: list[int], xy: np.ndarray) -> list[tuple[int, int, int]] | None:
    """Ear clipping of a counter-clockwise simple polygon (Eberly, "Triangulation by Ear Clipping",
    2002: only corners that are not strictly convex can lie in an ear, §2, looked up on a grid,
    `_Blockers`; a corner's ear test is done again only where a clip changed its triangle, the
    two neighbours'); None where it finds no ear. The smallest ear first (its triangle's bounding
    box, half its perimeter; ties by corner), each tested when it comes up: a corner that only
    a long thin ear would clip waits for the small ones (Eberly's walk, the next ear along the
    outline, fanned from one corner across a spiky outline, each long ear reading the corners
    along its box, and re-tested such an ear after every clip of its neighbour: a 160,000-corner
    star, half its corners reflex, took 21 s and a comb of long teeth minutes; the test of a
    corner that blocks no more is no cost: blocking corners that turn convex leave the grid).
    Since, other triangles than the walk's for polygons of more than _SMALL corners: `triangulate`
    clips smaller ones by _ear_clip_small, the walk's."""
    n = len(corners)
    xy = np.asarray(xy, np.float64)
    nxt, prv = [*range(1, n), 0], [n - 1, *range(n - 1)]
    grid = _Blockers(xy, _turn(xy[prv], xy, xy[nxt]) <= 0)  # reflex or flat: all an ear can hold
    p = grid.xy

    def size(b: int) -> float:
        (ax, ay), (bx, by), (cx, cy) = p[prv[b]], p[b], p[nxt[b]]
        return max(ax, bx, cx) - min(ax, bx, cx) + max(ay, by, cy) - min(ay, by, cy)

    convex = np.flatnonzero(_turn(xy[prv], xy, xy[nxt]) > 0).tolist()
    version = [0] * n
    heap = [(size(b), b, 0) for b in convex]
    heapq.heapify(heap)
    alive = [True] * n
    out = []
    left = n
    while left > 3:
        if not heap:
            return None
        _, b, seen = heapq.heappop(heap)
        if seen != version[b] or not alive[b] or not grid.is_ear(prv[b], b, nxt[b]):
            continue  # clipped, changed since, or no ear: tested again where a neighbour is clipped
        a, c = prv[b], nxt[b]
        out.append((corners[a], corners[b], corners[c]))
        alive[b] = False
        nxt[a], prv[c] = c, a
        left -= 1
        grid.exclude(b)
        for v in (a, c):  # only the neighbours' corners changed
            turn = _turn1(p[prv[v]], p[v], p[nxt[v]])
            grid.include(v, turn <= 0)
            version[v] += 1
            if turn > 0:
                heapq.heappush(heap, (size(v), v, version[v]))
    a = alive.index(True)
    out.append((corners[a], corners[nxt[a]], corners[nxt[nxt[a]]]))
    return out


def _turn1(o: tuple[float, float], a: tuple[float, float], b: tuple[float, float]) -> float:
    """_turn of one corner in Python floats: the same IEEE double operations."""
    return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])


class _Blockers:
    """The corners that can block an ear (blocking ones) on a uniform grid over the polygon's
    bounds, about four cells a blocking corner and as square as the bounds allow, each row's
    corners sorted by cell: the corners whose cell meets an ear's bounding box (grown by a margin)
    are all that can lie in the ear. A cell is a monotone function of a point, so a point inside a
    box has its cell within the box's corners' cells: the test's answers are those of a test of
    every corner. A corner that stops blocking leaves its row; one that starts (a degenerate or
    self-intersecting outline: clipping ears turns corners convex, never reflex, in a simple
    polygon, Eberly §2) joins it."""

    def __init__(self, xy: np.ndarray, blocking: np.ndarray):
        self.points = xy
        #: the corners as Python floats: an ear's own test in scalars, `_turn`'s operations
        self.xy = [(float(x), float(y)) for x, y in xy]
        #: which corners block, as a list (scalar reads) and an array (numpy's)
        self.mask, self.blocks = blocking.copy(), blocking.tolist()
        self.count = int(blocking.sum())
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
        #: 2^-32 of the corners' largest coordinate: far more than the rounding of the turn tests
        big = float(np.abs(xy).max()) if len(xy) else 0.0
        self.margin = big * 2.0**-32 if np.isfinite(big) else 0.0
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
        """The corners on the grid whose cells meet the box [x0, x1] × [y0, y1] grown by `margin`
        on every side: the turn tests, in floating point, can take a corner a rounding outside the
        box as inside the triangle (review: a corner 2^-53 off the box's edge, in the next cell,
        made an ear the test of every corner refuses; a whole cell more on every side read ~45
        corners of a 160,000-corner star's inner circle a cell, ~5 times the time)."""
        n, d = len(self.xy), self.margin
        lo, hi = self._cell(x0 - d, 0) * n, (self._cell(x1 + d, 0) + 1) * n
        out: list[int] = []
        for row in self.rows[self._cell(y0 - d, 1) : self._cell(y1 + d, 1) + 1]:
            if row:
                out += row[bisect.bisect_left(row, lo) : bisect.bisect_left(row, hi)]
        return [code % n for code in out]

    def is_ear(self, a: int, b: int, c: int) -> bool:
        """Whether corner b (between a and c) is an ear: convex, and no other corner that can
        block lies in the closed triangle abc. A corner at one of the ear's own corners (a
        polygon bridged to its hole, a "keyhole", repeats them) does not block: it fanned over
        the hole."""
        pa, pb, pc = self.xy[a], self.xy[b], self.xy[c]
        (ax, ay), (bx, by), (cx, cy) = pa, pb, pc
        if (bx - ax) * (cy - ay) - (by - ay) * (cx - ax) <= 0:
            return False  # a reflex or flat corner is no ear
        if not self.count:
            return True
        others = self.near(min(ax, bx, cx), min(ay, by, cy), max(ax, bx, cx), max(ay, by, cy))
        if len(others) > 64:  # in numpy
            idx = np.array(others, np.int64)
            idx = idx[self.mask[idx] & (idx != a) & (idx != b) & (idx != c)]
            p = self.points[idx]
            qa, qb, qc = self.points[a], self.points[b], self.points[c]
            inside = (_turn(qa, qb, p) >= 0) & (_turn(qb, qc, p) >= 0) & (_turn(qc, qa, p) >= 0)
            at_corner = np.zeros(len(p), bool)
            for q in (qa, qb, qc):
                at_corner |= (p[:, 0] == q[0]) & (p[:, 1] == q[1])
            return not np.any(inside & ~at_corner)
        xy, blocks = self.xy, self.blocks
        for v in others:
            if v == a or v == b or v == c or not blocks[v]:
                continue
            q = xy[v]
            if _turn1(pa, pb, q) >= 0 and _turn1(pb, pc, q) >= 0 and _turn1(pc, pa, q) >= 0:
                if not any(q[0] == r[0] and q[1] == r[1] for r in (pa, pb, pc)):
                    return False
        return True


def _turn(o: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The cross product (a − o) × (b − o) in 2D, row by row: > 0 where o, a, b turn left."""
    return (a[..., 0] - o[..., 0]) * (b[..., 1] - o[..., 1]) - (a[..., 1] - o[..., 1]) * (b[..., 0] - o[..., 0])
