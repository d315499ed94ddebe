"""Objects flagged "Analytic sphere" export as one exact sphere instead of their triangles."""

from __future__ import annotations

import numpy as np

from .errors import ExportError

#: The flag is a plain custom property, so files keep it and the export reads it without the add-on
#: (the add-on's "Analytic sphere" checkbox reads and writes this same property).
SPHERE_PROPERTY = "bvhlab_sphere"


def is_analytic_sphere(obj) -> bool:
    """True when the (original) object carries the "Analytic sphere" flag."""
    return bool(obj.original.get(SPHERE_PROPERTY, False))


def sphere_bounds(obj) -> np.ndarray:
    """float64 (2,3): the object-space bounds (min, max) of an evaluated object."""
    corners = np.array([tuple(c) for c in obj.bound_box], np.float64)  # 8 local-space corners
    return np.stack([corners.min(0), corners.max(0)])


#: What place_sphere gives for a sphere of no extent: no sphere.
NO_SPHERE = np.zeros(0, np.float32)


def place_sphere(bounds: np.ndarray, matrix_world: np.ndarray, name: str) -> np.ndarray:
    """(cx, cy, cz, radius) float32 of a flagged object from its object-space bounds (sphere_bounds)
    and world matrix: the centre is the world position of its bounds' centre (its location, for a
    sphere mesh around its origin), the radius the largest world-space half extent of its bounds
    (scale and modifiers included). NO_SPHERE for one of no extent (scaled to 0, a common way to
    hide instances, or an empty mesh): Blender renders nothing there, and the export failed."""
    lo, hi = bounds
    centre = matrix_world[:3, :3] @ ((lo + hi) / 2) + matrix_world[:3, 3]
    axis_scales = np.linalg.norm(matrix_world[:3, :3], axis=0)  # world length of each local axis
    radius = float(np.max((hi - lo) / 2 * axis_scales))
    if not (np.isfinite(centre).all() and np.isfinite(radius)):
        raise ExportError(f"analytic sphere '{name}' has a centre or radius that is not a finite number")
    if radius <= 0:
        return NO_SPHERE
    from .mesh import check_world_positions

    check_world_positions(np.array([centre - radius, centre + radius]), name)  # its box, centre ± radius
    return np.array([*centre, radius], np.float32)
