"""Small complete scenes (geometry, materials, camera, light) for tests, examples and the demo:
the report's five spheres (Figures 3–4) and a Whitted showcase. Deterministic, no files."""

from __future__ import annotations

import numpy as np

from ..scene import Camera, Light, Material, Scene


def quad(a, b, c, d) -> np.ndarray:
    """Two triangles a-b-c, a-c-d (counter-clockwise seen from the side the normal faces)."""
    return np.array([[a, b, c], [a, c, d]], np.float32)


def checker_floor(cells: int, size: float, z: float = 0.0):
    """A size×size floor centred at the origin, cells×cells squares; returns (triangles, material 0/1)."""
    tris, mats = [], []
    step = size / cells
    for i in range(cells):
        for j in range(cells):
            x0, y0 = -size / 2 + i * step, -size / 2 + j * step
            tris.append(quad((x0, y0, z), (x0 + step, y0, z), (x0 + step, y0 + step, z), (x0, y0 + step, z)))
            mats += [(i + j) % 2] * 2
    return np.concatenate(tris), np.array(mats, np.int32)


def box_mesh(lo, hi) -> np.ndarray:
    """The 12 triangles of an axis-aligned box, wound so every normal points outwards."""
    (x0, y0, z0), (x1, y1, z1) = lo, hi
    c = [(x0, y0, z0), (x1, y0, z0), (x1, y1, z0), (x0, y1, z0), (x0, y0, z1), (x1, y0, z1), (x1, y1, z1), (x0, y1, z1)]
    faces = [(0, 3, 2, 1), (4, 5, 6, 7), (0, 1, 5, 4), (2, 3, 7, 6), (1, 2, 6, 5), (3, 0, 4, 7)]
    return np.concatenate([quad(*(c[k] for k in f)) for f in faces])


def five_spheres() -> Scene:
    """The report's Figure 3: five spheres (and nothing else) where a median split differs from
    mean and SAH: three close together on the left, two apart on the right."""
    centers = [(-4.0, 0.0, 1.0), (-2.6, 0.4, 1.0), (-1.2, -0.3, 1.0), (1.5, 0.2, 1.0), (4.2, 0.0, 1.0)]
    spheres = np.array([(*c, 0.9 if k != 3 else 1.0) for k, c in enumerate(centers)], np.float32)
    materials = [Material((0.85, 0.25, 0.2)), Material((0.2, 0.5, 0.85)), Material((0.95, 0.8, 0.3))]
    return Scene(
        spheres=spheres,
        materials=materials,
        sphere_material=np.array([0, 1, 2, 0, 1], np.int32),
        camera=Camera((0.0, -11.0, 5.0), (0.0, 0.0, 0.8), fov_y=40.0),
        light=Light((-3.0, -6.0, 9.0), intensity=1.0),
        sky=(0.55, 0.7, 0.9),
    )


def whitted() -> Scene:
    """Reflective and transparent spheres over a checker floor (Whitted 1980's classic setup)."""
    floor, floor_mat = checker_floor(10, 16.0)
    spheres = np.array(
        [[-1.7, 0.6, 1.1, 1.1], [0.9, -0.6, 0.9, 0.9], [2.6, 1.4, 0.7, 0.7], [-0.2, 2.6, 1.3, 1.3]], np.float32
    )
    materials = [
        Material((0.9, 0.9, 0.85)),
        Material((0.8, 0.15, 0.1)),
        Material((0.95, 0.95, 0.95), reflective=0.85),  # mirror
        Material((1.0, 1.0, 1.0), reflective=0.1, transparent=0.85, ior=1.5),  # glass
        Material((0.2, 0.45, 0.9)),
        Material((0.9, 0.75, 0.2), reflective=0.3),
    ]
    return Scene(
        triangles=floor,
        spheres=spheres,
        materials=materials,
        tri_material=floor_mat,
        sphere_material=np.array([2, 3, 4, 5], np.int32),
        camera=Camera((0.5, -9.0, 3.6), (0.3, 0.5, 0.9), fov_y=42.0),
        light=Light((4.0, -5.0, 8.0), intensity=1.0),
        sky=(0.5, 0.68, 0.92),
    )
