"""The ear clipping's turn tests are exact in sign (ear_grid.py; Shewchuk 1997): simple outlines of
corners near one line, where the doubles' sign is wrong, are clipped into triangles that each turn
the polygon's way, hold no other corner and cover its area exactly (a review: with the doubles'
sign, 7 of 400 such polygons came out with flipped and overlapping slivers). Checked in integers:
each coordinate scaled exactly to a common denominator."""

from __future__ import annotations

import math
from fractions import Fraction

import numpy as np
import pytest

from bvhlab.library import polygons
from bvhlab.library.ear_grid import turn, turn1


def _integers(xy: np.ndarray) -> list[tuple[int, int]]:
    """The corners exactly, as integers over one common denominator."""
    exact = [(Fraction(float(x)), Fraction(float(y))) for x, y in xy]
    den = math.lcm(*(f.denominator for p in exact for f in p))
    return [(int(x * den), int(y * den)) for x, y in exact]


def _orient(o, a, b) -> int:
    return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])


def _simple(p: list[tuple[int, int]]) -> bool:
    """No two edges meet but neighbours at their shared corner, and no corner doubles back."""
    n = len(p)
    if len(set(p)) < n:
        return False

    def between(u, v, w) -> bool:  # v in the box of segment u, w
        return min(u[0], w[0]) <= v[0] <= max(u[0], w[0]) and min(u[1], w[1]) <= v[1] <= max(u[1], w[1])

    def touches(a, b, c, d) -> bool:
        s = [_orient(c, d, a), _orient(c, d, b), _orient(a, b, c), _orient(a, b, d)]
        if s[0] * s[1] < 0 and s[2] * s[3] < 0:
            return True
        return any(z == 0 and between(*e) for z, e in zip(s, [(c, a, d), (c, b, d), (a, c, b), (a, d, b)], strict=True))

    edges = [(p[i], p[(i + 1) % n]) for i in range(n)]
    for i in range(n):
        for j in range(i + 2, n - (i == 0)):
            if touches(*edges[i], *edges[j]):
                return False
    return all(
        _orient(p[i - 1], p[i], p[(i + 1) % n]) != 0
        or (p[i - 1][0] - p[i][0]) * (p[(i + 1) % n][0] - p[i][0])
        + (p[i - 1][1] - p[i][1]) * (p[(i + 1) % n][1] - p[i][1])
        <= 0
        for i in range(n)
    )


def _near_a_line(rng) -> np.ndarray:
    """A chain of corners on y = kx + c (off it by rounding alone), closed by one corner above it
    or by a second chain on a line a hair beside it (the review's family)."""
    m, k = int(rng.integers(40, 90)), rng.uniform(-3, 3)
    offset = rng.choice([0.0, 1.0, 1e3, 12345.678])
    x = np.sort(rng.uniform(0, 1, m)) + offset
    if rng.integers(2):
        x = np.cumsum(rng.uniform(0.5, 1.5, m)) / m + offset  # about evenly spaced
    y = k * x + rng.uniform(-1, 1)
    chain = np.stack([x, y], 1)
    apex = np.array([[x.mean(), y.mean() + rng.uniform(0.1, 2)]])
    if rng.integers(2):
        beside = np.stack([x[::-1], (k * x + 10.0 ** -rng.integers(3, 14))[::-1]], 1)
        return np.concatenate([chain, beside])
    return np.concatenate([chain, apex])


def test_outlines_near_a_line_are_clipped_exactly():
    rng, checked = np.random.default_rng(1), 0
    for _ in range(150):
        xy = _near_a_line(rng)
        p = _integers(xy)
        area = sum(p[i][0] * p[(i + 1) % len(p)][1] - p[(i + 1) % len(p)][0] * p[i][1] for i in range(len(p)))
        if area < 0:
            xy, p, area = xy[::-1], p[::-1], -area
        if not _simple(p):
            continue
        checked += 1
        tris = polygons.triangulate(range(len(xy)), np.concatenate([xy, np.zeros((len(xy), 1))], 1))
        assert len(tris) == len(xy) - 2
        total = 0
        for i, j, k in tris:
            twice = _orient(p[i], p[j], p[k])
            assert twice > 0, (checked, (i, j, k), "turned over")
            total += twice
            held = [v for v in range(len(p)) if v not in (i, j, k) and p[v] not in (p[i], p[j], p[k])]
            assert not any(
                _orient(p[i], p[j], p[v]) > 0 and _orient(p[j], p[k], p[v]) > 0 and _orient(p[k], p[i], p[v]) > 0
                for v in held
            ), (checked, (i, j, k), "holds a corner")
        assert total == area, checked
    assert checked > 60


@pytest.mark.parametrize(
    "o, a, b", [((0.1, 0.1), (0.2, 0.2), (0.3, 0.3)), ((1e-300, 0.0), (0.5, 1e300), (1.0, -1e300))]
)
def test_turn_of_collinear_and_extreme_corners_has_the_exact_sign(o, a, b):
    exact = (Fraction(a[0]) - Fraction(o[0])) * (Fraction(b[1]) - Fraction(o[1])) - (
        Fraction(a[1]) - Fraction(o[1])
    ) * (Fraction(b[0]) - Fraction(o[0]))
    sign = (exact > 0) - (exact < 0)
    assert np.sign(turn1(o, a, b)) == sign
    assert np.sign(turn(np.array([o]), np.array([a]), np.array([b]))[0]) == sign
