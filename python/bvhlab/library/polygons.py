"""Polygons of mesh files into triangles: a fan where the polygon is convex (its corners all turn
the same way about its normal), ear clipping where it is not (Eberly, "Triangulation by Ear
Clipping", 2002) — a fan over a concave polygon covers space outside it (a concave pentagon of
area 2.5 became triangles of area 3.5). Both give n − 2 triangles of the polygon's own corners.
Polygons of at most _SMALL corners are clipped along Eberly's walk (_ear_clip_small: the next ear
along the outline); larger ones smallest ear first (_ear_clip), whose triangles differ from the
walk's: the walk was quadratic on spiky outlines (a 160,000-corner star: 21 s, ~6 s since; a
160,000-corner comb of long teeth: minutes, ~1.3 s)."""

from __future__ import annotations

import heapq
import math
from collections.abc import Sequence

import numpy as np

from .ear_grid import Blockers as _Blockers
from .ear_grid import inside as _inside
from .ear_grid import turn as _turn
from .ear_grid import turn1 as _turn1


def triangulate(corners, positions: np.ndarray) -> list[tuple[int, int, int]]:
    """Triangles (vertex indices) covering the polygon whose vertices are `corners` (indices into
    `positions`, float (V, 3)), in the polygon's winding. Degenerate polygons (collinear, repeated
    or self-intersecting corners, where no ear is found) fall back to a fan; large ones whose ear
    tests keep failing (self-intersecting) fan the corners left after the ears clipped."""
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
    for each polygon (an OBJ of 490,000 quads peaked at 710 MiB through triangulate_all); a mesh of
    triangles alone is `corners` as they are."""
    if len(sizes) and (sizes == 3).all():
        return corners.reshape(-1, 3)
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


#: Polygons of at most this many corners are ear-clipped by _ear_clip_small (Eberly's walk, every
#: blocking corner tested: O(n²)); larger ones by _ear_clip (smallest ear first, a grid of the
#: blockers).
_SMALL = 32

#: _ear_clip's limit on wasted work: _BUDGET · n · log2(n) + _BUDGET_FLOOR corners and grid rows
#: read by ear tests that found no ear. Smallest ear first, a simple polygon's tests seldom fail:
#: none on stars (regular, random radii, random-walk radii), combs, spirals (also rotated), ~0.19 ·
#: n · log2(n) on maze outlines (10,000 to 170,000 corners, a helper's measurements), 0.25 on a
#: Hilbert curve's (a review's), an eighth of it;
#: a random self-intersecting one's fail on most corners, each reading a large part of the grid
#: (160,000 corners: 103 s, ~1 s with the limit). The floor (~0.1 s) keeps every polygon of up to
#: ~1,000 corners clear of the limit, whatever its shape.
_BUDGET = 2.0
_BUDGET_FLOOR = 1 << 20


def _ear_clip_small(corners: list[int], xy: list[list[float]]) -> list[tuple[int, int, int]] | None:
    """Ear clipping of a small polygon in Python floats along Eberly's walk (the next ear from the
    last one clipped), the clipping of every polygon of at most _SMALL corners, by triangulate and
    triangulate_all alike (the same triangles; the turn tests exact in sign, ear_grid's, as
    _Blockers.is_ear's), without numpy's cost on a handful of corners (~300 µs a concave hexagon:
    150,000 of them took 49 s in an OBJ, a helper's probe)."""
    n = len(corners)
    nxt, prv = [*range(1, n), 0], [n - 1, *range(n - 1)]

    def is_ear(a: int, b: int, c: int) -> bool:  # _Blockers.is_ear over every blocking corner
        pa, pb, pc = xy[a], xy[b], xy[c]
        if _turn1(pa, pb, pc) <= 0:
            return False
        return not any(_inside(pa, pb, pc, xy[v]) for v in range(n) if blocking[v] and v != a and v != b and v != c)

    alive = [True] * n
    blocking = [_turn1(xy[prv[v]], xy[v], xy[nxt[v]]) <= 0 for v in range(n)]
    ear = [is_ear(prv[b], b, nxt[b]) for b in range(n)]
    out: list[tuple[int, int, int]] = []
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
            blocking[v] = _turn1(xy[prv[v]], xy[v], xy[nxt[v]]) <= 0
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
    clips smaller ones by _ear_clip_small, the walk's. Where the tests that find no ear have read
    more than _BUDGET allows (a polygon that is not simple: ears are rare and large; Eberly's
    argument that one is always found, the two ears theorem, needs a simple polygon), the corners
    left are fanned, the ears clipped kept: n − 2 triangles of its corners, as a self-intersecting
    outline has no triangulation (random ones of 160,000 corners took 103 s, ~1 s since)."""
    n = len(corners)
    xy = np.asarray(xy, np.float64)
    nxt, prv = [*range(1, n), 0], [n - 1, *range(n - 1)]
    turns = _turn(xy[prv], xy, xy[nxt])
    grid = _Blockers(xy, turns <= 0)  # reflex or flat: all an ear can hold
    p = grid.xy

    def size(b: int) -> float:
        (ax, ay), (bx, by), (cx, cy) = p[prv[b]], p[b], p[nxt[b]]
        return max(ax, bx, cx) - min(ax, bx, cx) + max(ay, by, cy) - min(ay, by, cy)

    convex = np.flatnonzero(turns > 0).tolist()
    version = [0] * n
    heap = [(size(b), b, 0) for b in convex]
    heapq.heapify(heap)
    alive = [True] * n
    out: list[tuple[int, int, int]] = []
    left = n
    budget, wasted = _BUDGET * n * math.log2(n) + _BUDGET_FLOOR, 0
    while left > 3:
        if not heap:
            return None
        _, b, seen = heapq.heappop(heap)
        if seen != version[b] or not alive[b]:
            continue  # clipped, or changed since
        work = grid.reads
        if not grid.is_ear(prv[b], b, nxt[b]):  # tested again where a neighbour is clipped
            wasted += grid.reads - work
            if wasted > budget:  # not simple: the rest by a fan (any n - 2 triangles will do)
                rest = [alive.index(True)]
                while nxt[rest[-1]] != rest[0]:
                    rest.append(nxt[rest[-1]])
                return out + _fan([corners[v] for v in rest])
            continue
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
