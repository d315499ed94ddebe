"""The tracer's colour ramps as numpy arrays: one palette definition (shaders/tracer/
shade_colors.glsl, compiled into the core) for the CLI's images, the render engine's passes and
the viewport (issue 35). Colours are linear RGB in [0, 1]."""

from __future__ import annotations

import numpy as np

from . import _core


def heat(x) -> np.ndarray:
    """(n, 3) heat colours of values in [0, 1] (blue → cyan → green → yellow → red; clamped)."""
    return _core.heat_colors(np.ascontiguousarray(np.ravel(x), np.float32))


def diverging(x) -> np.ndarray:
    """(n, 3) colours of signed values in [-1, 1]: blue (-1) → white (0) → red (1); clamped."""
    return _core.diverging_colors(np.ascontiguousarray(np.ravel(x), np.float32))


def depth(depths) -> np.ndarray:
    """(n, 3) overlay line colours of tree depths (hues a golden angle apart)."""
    return _core.depth_colors(np.ascontiguousarray(np.ravel(depths), np.uint32))


def scaled(values: np.ndarray, lo: float, hi: float) -> np.ndarray:
    """`values` mapped onto the heat ramp's [0, 1]: lo → 0, hi → 1 (float32, same shape)."""
    return ((np.asarray(values, np.float64) - lo) / (hi - lo)).astype(np.float32)


def rgba(rgb: np.ndarray, shape: tuple) -> np.ndarray:
    """(*shape, 4) float32 image of (n, 3) colours, alpha 1."""
    out = np.ones((*shape, 4), np.float32)
    out[..., :3] = rgb.reshape(*shape, 3)
    return out


def heat_image(values: np.ndarray, lo: float, hi: float) -> np.ndarray:
    """(H, W, 4) heat colours of an (H, W) plane over the range lo..hi."""
    return rgba(heat(scaled(values, lo, hi)), values.shape)


def diverging_image(values: np.ndarray, span: float) -> np.ndarray:
    """(H, W, 4) diverging colours of an (H, W) plane of signed values, ±span at the ends."""
    return rgba(diverging(np.asarray(values, np.float64) / span), values.shape)
