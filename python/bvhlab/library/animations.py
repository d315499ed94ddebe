"""Generated animations for the per-frame dynamic-BVH experiment (issue 34; the report's §1 and
§5.2 name refitting and partial rebuilds for dynamic scenes as the step after it): each is a
function of the frame's phase t in [0, 1] giving the frame's triangles, the same count every
frame, so that every update policy applies.

- "wave": a grid (250,632 triangles at the default size) with a travelling wave and a tall bump
  sweeping across it, so that some parts of a refit tree go bad and others do not;
- "crowd": a floor with pillars (static) and hundreds of small knots flying along helices at
  their own speeds through it, the rigid-objects case."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from . import procedural


def wave(size: int = 354) -> Callable[[float], np.ndarray]:
    """A (size × size)-quad grid: 2·size² triangles (the default 250,632)."""
    u = np.linspace(0.0, 1.0, size + 1, dtype=np.float64)
    x, y = np.meshgrid(u, u, indexing="ij")

    def frame(t: float) -> np.ndarray:
        bump_x = 0.1 + 0.8 * t
        z = 0.03 * np.sin(20 * x + 6 * t) + 0.4 * np.exp(-((x - bump_x) ** 2 + (y - 0.5) ** 2) / 0.005)
        p = np.stack([x, y, z], -1).astype(np.float32)
        a, b, c, d = p[:-1, :-1], p[1:, :-1], p[:-1, 1:], p[1:, 1:]
        tris = np.concatenate([np.stack([a, b, c], -2), np.stack([b, d, c], -2)]).reshape(-1, 3, 3)
        return np.ascontiguousarray(tris)

    return frame


def crowd(count: int = 300, knot_triangles: int = 480, seed: int = 1) -> Callable[[float], np.ndarray]:
    """`count` knots of `knot_triangles` each, flying through a static room of pillars."""
    rng = np.random.default_rng(seed)
    floor = procedural.grid_surface(
        40, 40, lambda u, v: np.stack([u * 20 - 10, v * 20 - 10, 0 * u], -1), u_closed=False, v_closed=False
    )
    pillars = [
        procedural.grid_surface(
            12,
            8,
            lambda u, v, cx=cx, cy=cy: np.stack([cx + 0.4 * np.cos(u), cy + 0.4 * np.sin(u), v * 6], -1),
            v_closed=False,
        )
        for cx in (-6.0, -2.0, 2.0, 6.0)
        for cy in (-6.0, -2.0, 2.0, 6.0)
    ]
    static = np.concatenate([floor, *pillars]).astype(np.float32)
    knot = procedural.torus_knot(knot_triangles).astype(np.float64)
    knot = (knot - knot.reshape(-1, 3).mean(0)) * (0.35 / np.abs(knot).max())
    radius, height = rng.uniform(1.0, 9.0, count), rng.uniform(0.5, 5.5, count)
    phase, speed = rng.uniform(0, 2 * np.pi, count), rng.uniform(0.5, 2.0, count) * rng.choice([-1, 1], count)

    def frame(t: float) -> np.ndarray:
        angle = phase + 2 * np.pi * speed * t
        centres = np.stack(
            [radius * np.cos(angle), radius * np.sin(angle), height + 0.8 * np.sin(3 * angle)], -1
        )  # (count, 3)
        moving = knot[None] + centres[:, None, None, :]
        return np.ascontiguousarray(np.concatenate([static, moving.reshape(-1, 3, 3).astype(np.float32)]))

    return frame


#: name → (make, description); make() gives the frame function at the default size.
ANIMATIONS: dict[str, tuple[Callable[..., Callable[[float], np.ndarray]], str]] = {
    "wave": (wave, "a 250,632-triangle grid with a travelling wave and a sweeping bump"),
    "crowd": (crowd, "300 knots (144,000 triangles) flying among pillars over a floor (150,272 in all)"),
}
