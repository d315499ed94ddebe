"""Generated animations for the per-frame dynamic-BVH experiment (issue 34; the report's §1 and
§5.2 name refitting and partial rebuilds for dynamic scenes as the step after it): each is a
function of the frame's phase t in [0, 1] giving the frame's triangles, the same count every
frame, so that every update policy applies.

- "wave": a grid (250,632 triangles at the default size) with a travelling wave and a tall bump
  sweeping across it, so that some parts of a refit tree go bad and others do not;
- "crowd": a floor with pillars (static) and hundreds of small knots flying along helices at
  their own speeds through it, the rigid-objects case.

The two animated .blend files (blender_scenes/make_animated.py) play the same motions in Blender
with geometry nodes over frames 1..ANIMATION_FRAMES: `wave` itself, and `CrowdPaths` (atrium_crowd)
for knots flying through the bundled atrium as instances of one mesh; the tests compare the
exported frames with these functions."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from . import procedural

#: The frames of the animated .blend files: Blender frames 1..ANIMATION_FRAMES are t = 0..1.
ANIMATION_FRAMES = 24


def frame_phase(frame: int, first: int = 1, last: int = ANIMATION_FRAMES) -> float:
    """t in [0, 1] of a frame in first..last (the .blend files' time: their geometry nodes say the same)."""
    return (frame - first) / max(last - first, 1)


@dataclass(frozen=True)
class CrowdPaths:
    """Where each of a crowd's knots is at phase t: on an ellipse of half-axes (ax·radius,
    ay·radius) at `height`, bobbing by 0.8·sin(3·angle), its angle phase + 2π·speed·t (speed in
    turns over the animation); the atrium's knots also turn about z by that angle."""

    radius: np.ndarray
    height: np.ndarray
    phase: np.ndarray
    speed: np.ndarray
    ax: float = 1.0
    ay: float = 1.0

    def angles(self, t: float) -> np.ndarray:
        return self.phase + 2 * np.pi * self.speed * t

    def centres(self, t: float) -> np.ndarray:
        """(count, 3) float64."""
        a = self.angles(t)
        return np.stack(
            [self.ax * self.radius * np.cos(a), self.ay * self.radius * np.sin(a), self.height + 0.8 * np.sin(3 * a)],
            -1,
        )

    def transforms(self, t: float) -> np.ndarray:
        """(count, 3, 4) float64 object-to-world: a turn about z by the angle, then the centre."""
        a = self.angles(t)
        out = np.zeros((len(a), 3, 4))
        out[:, 0, 0], out[:, 0, 1], out[:, 1, 0], out[:, 1, 1] = np.cos(a), -np.sin(a), np.sin(a), np.cos(a)
        out[:, 2, 2] = 1.0
        out[:, :, 3] = self.centres(t)
        return out


def crowd_knot(triangles: int = 480) -> np.ndarray:
    """The crowd's knot: a torus knot centred on the origin, 0.35 at its farthest (float64)."""
    knot = procedural.torus_knot(triangles).astype(np.float64)
    return (knot - knot.reshape(-1, 3).mean(0)) * (0.35 / np.abs(knot).max())


def atrium_crowd(count: int = 300, seed: int = 2) -> CrowdPaths:
    """Knots flying down the bundled atrium's nave (x in ±10, between its colonnades at y = ±3.5,
    under its gallery): 0.1 to 0.4 turns each way over the animation."""
    rng = np.random.default_rng(seed)
    radius, height = rng.uniform(0.2, 1.0, count), rng.uniform(0.9, 6.6, count)
    phase, speed = rng.uniform(0, 2 * np.pi, count), rng.uniform(0.1, 0.4, count) * rng.choice([-1, 1], count)
    return CrowdPaths(radius, height, phase, speed, ax=10.0, ay=2.6)


def wave(size: int = 354) -> Callable[[float], np.ndarray]:
    """A (size × size)-quad grid: 2·size² triangles (the default 250,632)."""
    u = np.linspace(0.0, 1.0, size + 1, dtype=np.float64)
    x, y = np.meshgrid(u, u, indexing="ij")

    def frame(t: float) -> np.ndarray:
        bump_x = 0.1 + 0.8 * t
        z = 0.03 * np.sin(20 * x + 6 * t) + 0.4 * np.exp(-((x - bump_x) ** 2 + (y - 0.5) ** 2) / 0.005)
        p = np.stack([x, y, z], -1).astype(np.float32)
        a, b, c, d = p[:-1, :-1], p[1:, :-1], p[:-1, 1:], p[1:, 1:]
        # each quad split along its a-d diagonal, as Blender triangulates the grid's quads
        tris = np.concatenate([np.stack([a, b, d], -2), np.stack([a, d, c], -2)]).reshape(-1, 3, 3)
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
    knot = crowd_knot(knot_triangles)
    radius, height = rng.uniform(1.0, 9.0, count), rng.uniform(0.5, 5.5, count)
    phase, speed = rng.uniform(0, 2 * np.pi, count), rng.uniform(0.5, 2.0, count) * rng.choice([-1, 1], count)
    paths = CrowdPaths(radius, height, phase, speed)

    def frame(t: float) -> np.ndarray:
        moving = knot[None] + paths.centres(t)[:, None, None, :]
        return np.ascontiguousarray(np.concatenate([static, moving.reshape(-1, 3, 3).astype(np.float32)]))

    return frame


#: name → (make, description); make() gives the frame function at the default size.
ANIMATIONS: dict[str, tuple[Callable[..., Callable[[float], np.ndarray]], str]] = {
    "wave": (wave, "a 250,632-triangle grid with a travelling wave and a sweeping bump"),
    "crowd": (crowd, "300 knots (144,000 triangles) flying among pillars over a floor (150,272 in all)"),
}
