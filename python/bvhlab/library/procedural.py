"""Procedural scenes for tests, benchmarks and the demo, generated in numpy (no files needed).

Every generator is deterministic (seeded) and returns float32 (T,3,3) triangles or a Scene.
"""

from __future__ import annotations

import math

import numpy as np


def grid_surface(u_count: int, v_count: int, point, u_closed: bool = True, v_closed: bool = True) -> np.ndarray:
    """Triangulate a parametric surface point(u, v) -> (..., 3) sampled on a u×v grid, (u, v) in [0, 1).
    Returns 2·u_count·v_count triangles (fewer edges when a direction is open)."""
    nu, nv = u_count + (0 if u_closed else 1), v_count + (0 if v_closed else 1)
    u = np.arange(nu) / (u_count if u_closed else u_count)
    v = np.arange(nv) / (v_count if v_closed else v_count)
    uu, vv = np.meshgrid(u, v, indexing="ij")
    p = np.asarray(point(uu, vv), np.float64)  # (nu, nv, 3)
    i = np.arange(u_count)[:, None]
    j = np.arange(v_count)[None, :]
    i1 = (i + 1) % nu
    j1 = (j + 1) % nv
    a, b, c, d = p[i, j], p[i1, j], p[i1, j1], p[i, j1]
    tris = np.stack([np.stack([a, b, c], -2), np.stack([a, c, d], -2)], 2)  # (U, V, 2, 3, 3)
    return np.ascontiguousarray(tris.reshape(-1, 3, 3), np.float32)


def torus_knot(
    triangles: int, p: int = 2, q: int = 3, tube: float = 0.35, bumps: float = 0.04, scale: float = 1.0
) -> np.ndarray:
    """A bumpy (p, q) torus-knot tube of about `triangles` triangles: a detailed, curved mesh with
    triangles of varying size, the stand-in for the report's high-poly models."""
    v_count = max(3, int(round(math.sqrt(triangles / 2 / 12))))
    u_count = max(3, int(round(triangles / 2 / v_count)))

    def curve(t):
        phi = 2 * np.pi * t
        r = 2 + np.cos(q * phi)
        return np.stack([r * np.cos(p * phi), r * np.sin(p * phi), -np.sin(q * phi)], -1)

    def point(u, v):
        c = curve(u)
        tangent = curve(u + 1e-4) - curve(u - 1e-4)
        tangent /= np.linalg.norm(tangent, axis=-1, keepdims=True)
        normal = np.cross(tangent, [0.0, 0.0, 1.0])
        normal /= np.linalg.norm(normal, axis=-1, keepdims=True)
        binormal = np.cross(tangent, normal)
        theta = 2 * np.pi * v
        radius = tube * (1 + bumps * np.sin(37 * 2 * np.pi * u) * np.sin(11 * theta))
        off = radius[..., None] * (np.cos(theta)[..., None] * normal + np.sin(theta)[..., None] * binormal)
        return (c + off) * scale

    return grid_surface(u_count, v_count, point)


def box_room(size: float, divisions: int) -> np.ndarray:
    """The six inner faces of a cube of side `size` centred at the origin (floor at -size/2),
    each a divisions×divisions grid: large triangles around whatever is placed inside."""
    h = size / 2
    faces = []
    for axis in range(3):
        for sign in (-1.0, 1.0):
            a1, a2 = [k for k in range(3) if k != axis]

            def point(u, v, axis=axis, sign=sign, a1=a1, a2=a2):
                out = np.zeros(u.shape + (3,))
                out[..., axis] = sign * h
                out[..., a1] = (u - 0.5) * size
                out[..., a2] = (v - 0.5) * size
                return out

            faces.append(grid_surface(divisions, divisions, point, u_closed=False, v_closed=False))
    return np.concatenate(faces)


def model_in_room(triangles: int, seed: int = 0) -> np.ndarray:
    """A detailed model (torus knot) off-centre in a room 40 times its size, with a few pieces of
    furniture: the non-uniform case where median splits go wrong (the "teapot in a stadium")."""
    rng = np.random.default_rng(seed)
    room = box_room(120.0, 24)  # 3456 large triangles
    furniture = [torus_knot(2000, 3, 5, scale=3.0) + rng.uniform(-45, 45, 3).astype(np.float32) for _ in range(4)]
    knot_count = max(0, triangles - len(room) - sum(len(f) for f in furniture))
    knot = torus_knot(knot_count) + np.array([20.0, 25.0, -50.0], np.float32)
    return np.ascontiguousarray(np.concatenate([room, *furniture, knot]), np.float32)


def repeated_row(triangles: int, copies: int = 20) -> np.ndarray:
    """A torus knot of about triangles/copies triangles repeated `copies` times in a row along x:
    repeated geometry (what instancing would store once) laid out flat, long in one axis."""
    knot = torus_knot(max(1, triangles // copies))
    step = np.float32(7.0)  # the knot spans about 6.7 units
    return np.ascontiguousarray(np.concatenate([knot + np.array([k * step, 0, 0], np.float32) for k in range(copies)]))


def rods(triangles: int, count: int = 2000, sections: int = 8, seed: int = 0) -> np.ndarray:
    """`count` long thin open cylinders (radius 0.02, length 2 to 8) at random angles and places in a
    box of side 10, each cut along its length into segments so that there are about `triangles`
    triangles in all: long thin triangles whose boxes are mostly empty and overlap along the rods'
    diagonals (the case spatial splits are for)."""
    rng = np.random.default_rng(seed)
    segments = max(1, triangles // (count * 2 * sections))

    def unit(u, v):  # a cylinder of radius 1 along z from 0 to 1
        angle = 2 * np.pi * u
        return np.stack([np.cos(angle), np.sin(angle), v], -1)

    template = grid_surface(sections, segments, unit, v_closed=False).astype(np.float64)
    axis = rng.normal(size=(count, 3))
    axis /= np.linalg.norm(axis, axis=1, keepdims=True)
    side = np.cross(axis, np.where(np.abs(axis[:, :1]) < 0.9, [[1.0, 0, 0]], [[0, 1.0, 0]]))
    side /= np.linalg.norm(side, axis=1, keepdims=True)
    other = np.cross(axis, side)
    length = rng.uniform(2.0, 8.0, count)
    radius = 0.02
    # object → world: columns side·r, other·r, axis·length; each rod centred at a random point
    linear = np.stack([side * radius, other * radius, axis * length[:, None]], 2)  # (count, 3, 3)
    centre = rng.uniform(-5.0, 5.0, (count, 3)) - axis * length[:, None] / 2
    world = np.einsum("nij,tvj->ntvi", linear, template) + centre[:, None, None, :]
    return np.ascontiguousarray(world.reshape(-1, 3, 3), np.float32)


def model_in_vast_room(triangles: int) -> np.ndarray:
    """A torus knot of about `triangles` triangles (6.7 units across) off-centre in an empty room
    10,000 units wide: almost all of the scene's box is empty space around one small dense mesh."""
    room = box_room(10_000.0, 8)
    knot = torus_knot(max(1, triangles - len(room))) + np.array([300.0, -200.0, -4_990.0], np.float32)
    return np.ascontiguousarray(np.concatenate([room, knot]), np.float32)


def random_triangles(n: int, size: float = 0.01, seed: int = 0) -> np.ndarray:
    """n small triangles uniformly at random in the unit cube: the uniform case."""
    rng = np.random.default_rng(seed)
    centers = rng.random((n, 1, 3), np.float32)
    offsets = (rng.random((n, 3, 3), np.float32) - 0.5) * size
    return np.ascontiguousarray(centers + offsets, np.float32)


def random_spheres(n: int, radius: float = 0.02, seed: int = 0) -> np.ndarray:
    """n spheres uniformly at random in the unit cube (report §4.2)."""
    rng = np.random.default_rng(seed)
    s = np.empty((n, 4), np.float32)
    s[:, :3] = rng.random((n, 3))
    s[:, 3] = radius * (0.5 + rng.random(n))
    return s


def camera_rays(tris: np.ndarray, width: int, height: int, fov_y: float = 45.0):
    """Coherent primary rays of a pinhole camera that frames the geometry (the default camera)."""
    from ..scene import default_camera

    lo, hi = tris.reshape(-1, 3).min(0), tris.reshape(-1, 3).max(0)
    cam = default_camera((lo, hi))
    pos, look, up = (np.array(v, np.float64) for v in (cam.position, cam.look_at, cam.up))
    fwd = look - pos
    fwd /= np.linalg.norm(fwd)
    right = np.cross(fwd, up)
    right /= np.linalg.norm(right)
    true_up = np.cross(right, fwd)
    tan = math.tan(math.radians(fov_y) / 2)
    ys, xs = np.mgrid[0:height, 0:width]
    px = ((xs + 0.5) / width * 2 - 1) * tan * width / height
    py = (1 - (ys + 0.5) / height * 2) * tan
    d = fwd + px[..., None] * right + py[..., None] * true_up
    d /= np.linalg.norm(d, axis=-1, keepdims=True)
    origins = np.broadcast_to(pos, d.shape).reshape(-1, 3)
    return np.ascontiguousarray(origins, np.float32), np.ascontiguousarray(d.reshape(-1, 3), np.float32)


def random_rays(tris: np.ndarray, n: int, seed: int = 0):
    """Incoherent rays: origins uniform in the geometry's bounds, directions uniform on the sphere."""
    rng = np.random.default_rng(seed)
    lo, hi = tris.reshape(-1, 3).min(0), tris.reshape(-1, 3).max(0)
    origins = lo + rng.random((n, 3)) * (hi - lo)
    d = rng.normal(size=(n, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    return np.ascontiguousarray(origins, np.float32), np.ascontiguousarray(d, np.float32)
