"""Polygons of mesh files into triangles: a fan where the polygon is convex (its corners all turn
the same way about its normal), ear clipping where it is not (Eberly, "Triangulation by Ear
Clipping", 2002) — a fan over a concave polygon covers space outside it (a concave pentagon of
area 2.5 became triangles of area 3.5). Both give n − 2 triangles of the polygon's own corners."""

from __future__ import annotations

import bisect
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
    return _ear_clip(corners, _projected(p, normal)) or _fan(corners)


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
    """_ear_clip of a small polygon in Python floats: the same ears in the same order, by the same
    IEEE double operations (its grid only leaves out corners that cannot block; here every corner
    that can is tested), without numpy's cost on a handful of corners (~300 µs a concave hexagon:
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
        # _ear_clip's walk: the next ear from b on, else the first (its 64-corner window holds a
        # whole small polygon)
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
    """Ear clipping of a counter-clockwise simple polygon; None where it finds no ear. Each corner's
    ear test is kept and done again only for the two neighbours of a clipped ear (the rest keep
    theirs), and only corners that are not strictly convex can lie in an ear (Eberly §2), looked
    up on a grid (`_Blockers`): an ear reads the corners near it, not all of them (a 32,000-corner
    zigzag outline, half its corners reflex: 11.1 s with every such corner tested for every ear,
    3.1-3.6 s now; the same triangles)."""
    n = len(corners)
    xy = np.asarray(xy, np.float64)
    nxt, prv = np.roll(np.arange(n), -1), np.roll(np.arange(n), 1)
    alive = np.ones(n, bool)
    blocking = _turn(xy[prv], xy, xy[nxt]) <= 0  # reflex or flat: the only corners an ear can hold
    grid = _Blockers(xy, blocking)
    ear = np.array([grid.is_ear(prv[b], b, nxt[b], blocking) for b in range(n)])
    out = []
    b, left = 0, n
    while left > 3:
        # the next ear on from the last one clipped (the walk Eberly's ear list makes): mostly
        # within a few corners, so looked for there before in the whole polygon
        near = np.flatnonzero(ear[b : b + 64] & alive[b : b + 64])
        if len(near):
            b += int(near[0])
        else:
            candidates = np.flatnonzero(ear & alive)
            if not len(candidates):
                return None
            after = candidates[candidates >= b]
            b = int(after[0] if len(after) else candidates[0])
        a, c = prv[b], nxt[b]
        out.append((corners[a], corners[b], corners[c]))
        alive[b] = blocking[b] = ear[b] = False
        nxt[a], prv[c] = c, a
        left -= 1
        for v in (a, c):  # only the neighbours' corners changed
            blocking[v] = _turn(xy[prv[v]], xy[v], xy[nxt[v]]) <= 0
            grid.include(v, blocking[v])
        for v in (a, c):
            ear[v] = grid.is_ear(prv[v], v, nxt[v], blocking)
        b = c
    a = int(np.flatnonzero(alive)[0])
    out.append((corners[a], corners[nxt[a]], corners[nxt[nxt[a]]]))
    return out


class _Blockers:
    """The corners that can block an ear, on a uniform grid of about n cells over the polygon's
    bounds, sorted by cell: the corners whose cell lies in an ear's bounding box (or next to it:
    near) are all that can lie in the ear. A cell is a monotone function of a point, so a point
    inside a box has its cell within the box's corners' cells: the test's answers are those of a
    test of every corner.
    Clipping ears turns corners convex, never reflex, in a simple polygon (Eberly §2); a corner
    that does turn reflex (a degenerate or self-intersecting outline) joins a list read by every
    ear. Corners that stopped blocking stay on the grid and are passed over by the caller."""

    def __init__(self, xy: np.ndarray, blocking: np.ndarray):
        self.points = xy
        #: the corners as Python floats: an ear's own test in scalars (~100,000 ears in a large
        #: outline), the same IEEE double operations as `_turn`'s
        self.xy = [(float(x), float(y)) for x, y in xy]
        with np.errstate(over="ignore", invalid="ignore"):
            span = xy.max(axis=0) - xy.min(axis=0)
        # one cell where the bounds are not finite (corners near ±1e308: the reader refuses them
        # after; a grid of them raised "cannot convert float NaN to integer" first)
        self.cells = max(1, int(np.sqrt(len(xy)))) if np.isfinite(span).all() else 1
        self.lo = [float(v) for v in xy.min(axis=0)] if self.cells > 1 else [0.0, 0.0]
        self.size = [float(v / self.cells) if v > 0 else 1.0 for v in span] if self.cells > 1 else [1.0, 1.0]
        cell = (
            np.clip(((xy - self.lo) / self.size).astype(np.int64), 0, self.cells - 1)
            if self.cells > 1
            else np.zeros((len(xy), 2), np.int64)
        )
        keys = cell[:, 1] * self.cells + cell[:, 0]
        on_grid = np.flatnonzero(blocking)
        self.order = on_grid[np.argsort(keys[on_grid], kind="stable")]
        self.keys = keys[self.order].tolist()
        self.on_grid = blocking.copy()
        self.extra: list[int] = []

    def _cell(self, x: float, axis: int) -> int:
        """The cell of coordinate x along axis, as __init__ computes it for every corner."""
        if self.cells == 1:
            return 0
        return min(max(int((x - self.lo[axis]) / self.size[axis]), 0), self.cells - 1)

    def include(self, v: int, blocks: bool) -> None:
        if blocks and not self.on_grid[v]:
            self.on_grid[v] = True
            self.extra.append(v)

    def near(self, x0: float, y0: float, x1: float, y1: float) -> list[np.ndarray]:
        """The corners on the grid whose cells meet the box [x0, x1] × [y0, y1] or a cell next to
        it, and the extra ones, as arrays. One cell more on every side: the turn tests, in floating
        point, can take a corner a rounding outside the box as inside the triangle (review: a
        corner 2^-53 off the box's edge, in the next cell, made an ear the test of every corner
        refuses)."""
        cx0, cx1 = max(self._cell(x0, 0) - 1, 0), min(self._cell(x1, 0) + 1, self.cells - 1)
        rows = range(max(self._cell(y0, 1) - 1, 0), min(self._cell(y1, 1) + 1, self.cells - 1) + 1)
        parts = []
        for row in rows:
            start = bisect.bisect_left(self.keys, row * self.cells + cx0)
            end = bisect.bisect_right(self.keys, row * self.cells + cx1, lo=start)
            if end > start:
                parts.append(self.order[start:end])
        if self.extra:
            parts.append(np.array(self.extra, np.int64))
        return parts

    def is_ear(self, a: int, b: int, c: int, blocking: np.ndarray) -> bool:
        """Whether corner b (between a and c) is an ear: convex, and no other corner that can
        block lies in the closed triangle abc. A corner at one of the ear's own corners (a
        polygon bridged to its hole, a "keyhole", repeats them) does not block: it fanned over
        the hole."""
        (ax, ay), (bx, by), (cx, cy) = self.xy[a], self.xy[b], self.xy[c]
        if (bx - ax) * (cy - ay) - (by - ay) * (cx - ax) <= 0:
            return False  # a reflex or flat corner is no ear
        parts = self.near(min(ax, bx, cx), min(ay, by, cy), max(ax, bx, cx), max(ay, by, cy))
        if not parts:
            return True
        others = parts[0] if len(parts) == 1 else np.concatenate(parts)
        others = others[blocking[others] & (others != a) & (others != b) & (others != c)]
        if not len(others):
            return True
        pa, pb, pc = self.points[a], self.points[b], self.points[c]
        p = self.points[others]
        inside = (_turn(pa, pb, p) >= 0) & (_turn(pb, pc, p) >= 0) & (_turn(pc, pa, p) >= 0)
        at_corner = np.zeros(len(p), bool)
        for q in (pa, pb, pc):
            at_corner |= (p[:, 0] == q[0]) & (p[:, 1] == q[1])
        return not np.any(inside & ~at_corner)


def _turn(o: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The cross product (a − o) × (b − o) in 2D, row by row: > 0 where o, a, b turn left."""
    return (a[..., 0] - o[..., 0]) * (b[..., 1] - o[..., 1]) - (a[..., 1] - o[..., 1]) * (b[..., 0] - o[..., 0])
