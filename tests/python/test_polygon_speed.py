"""Large spiky polygons (bvhlab.library.polygons): a star of 40,000 corners, half of them reflex,
triangulated in a child process within a generous time (Eberly's walk took 21 s for 160,000
corners and minutes for a comb of long teeth: quadratic), and its triangles checked against an
independent computation: n − 2 of its own corners, none turned over, their areas summing to the
polygon's (shoelace)."""

import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

from bvhlab.library import polygons


def star(n: int) -> np.ndarray:
    """n corners around a circle, alternately at radius 1 and 0.5: spikes, every other corner reflex."""
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    r = np.where(np.arange(n) % 2 == 0, 1.0, 0.5)
    return np.stack([r * np.cos(t), r * np.sin(t)], 1)


def comb(teeth: int) -> np.ndarray:
    """A comb of long thin teeth (height 50, width 1) whose gaps lie on one line."""
    ring = [(0.0, -1.0), (float(teeth), -1.0)]
    for i in range(teeth - 1, -1, -1):
        ring += [(i + 1.0, 50.0), (i + 0.5, 0.0)]
    return np.array(ring)


def check(xy: np.ndarray, triangles) -> None:
    t = np.array(triangles)
    assert t.shape == (len(xy) - 2, 3) and t.min() >= 0 and t.max() < len(xy)
    a, b, c = xy[t[:, 0]], xy[t[:, 1]], xy[t[:, 2]]
    areas = 0.5 * ((b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0]))
    x, y = xy.T
    shoelace = 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))  # signed
    assert (areas * np.sign(shoelace) >= 0).all()  # the polygon's winding, none turned over
    assert areas.sum() == pytest.approx(shoelace, rel=1e-9)
    # every edge of the polygon is an edge of a triangle, in the polygon's direction
    edges = np.concatenate([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]])
    ring = np.stack([np.arange(len(xy)), np.roll(np.arange(len(xy)), -1)], 1)
    keys = set(map(tuple, edges.tolist()))
    assert all(tuple(e) in keys for e in ring.tolist())


@pytest.mark.parametrize("xy", [star(2000), comb(1000), star(2001)[::-1]], ids=["star", "comb", "clockwise"])
def test_spiky_polygons_are_covered_exactly(xy):
    """Stars and combs in both windings: valid triangulations of their own corners."""
    xyz = np.concatenate([xy, np.zeros((len(xy), 1))], 1)
    check(xy, polygons.triangulate(list(range(len(xy))), xyz))


def test_a_star_of_40000_corners_is_triangulated_in_seconds():
    """~1 s now; 3.2 s before at 40,000 corners and 21 s at 160,000 (quadratic), so the limit
    (in a child process, not to hang the run) is generous and still fails the quadratic clipping
    of a 4× larger comb-like outline: a star and a comb of 40,000 corners each."""
    code = textwrap.dedent(
        """
        import numpy as np, sys
        sys.path[:0] = [%r]
        from test_polygon_speed import star, comb, check
        from bvhlab.library import polygons
        for xy in (star(40000), comb(80000)):
            xyz = np.concatenate([xy, np.zeros((len(xy), 1))], 1)
            check(xy, polygons.triangulate(list(range(len(xy))), xyz))
        """
    ) % str(Path(__file__).parent)
    subprocess.run([sys.executable, "-c", code], check=True, timeout=60)
