"""A scattered, instanced scene (issue 34): what a geometry-nodes scatter makes in Blender, without
Blender. Few meshes, many placements: a two-level tree stores each mesh once. Deterministic."""

from __future__ import annotations

import numpy as np

from ..scene import Camera, Light, Material, Scene
from . import procedural
from .showcase import box_mesh, checker_floor


def knot_field(count: int = 2000, knot_triangles: int = 20_000, seed: int = 0) -> Scene:
    """`count` instances of a bumpy torus knot (`knot_triangles` triangles) and of a box "rock"
    scattered over a checker floor with random turns about Z, tilts and sizes (uniform scale
    0.4-1.2): about count × knot_triangles / 2 triangles in the world, stored once per mesh."""
    if count < 1:
        raise ValueError(f"count must be >= 1, got {count}")
    rng = np.random.default_rng(seed)
    side = 3.0 * np.sqrt(count)
    floor, floor_mat = checker_floor(16, side * 1.1)
    knot = procedural.torus_knot(knot_triangles, scale=0.5)
    knot[:, :, 2] += 0.4 - knot[:, :, 2].min()  # resting on the floor, in its own space
    rock = box_mesh((-0.6, -0.4, 0.0), (0.6, 0.4, 0.7))
    mesh = rng.integers(1, 3, count)  # 1: knot, 2: rock
    yaw = rng.uniform(0, 2 * np.pi, count)
    tilt = rng.normal(0, 0.15, count)
    scale = rng.uniform(0.4, 1.2, count)
    cy, sy, ct, st = np.cos(yaw), np.sin(yaw), np.cos(tilt), np.sin(tilt)
    zero, one = np.zeros(count), np.ones(count)
    turn = np.stack([np.stack([cy, -sy, zero], -1), np.stack([sy, cy, zero], -1), np.stack([zero, zero, one], -1)], -2)
    lean = np.stack([np.stack([one, zero, zero], -1), np.stack([zero, ct, -st], -1), np.stack([zero, st, ct], -1)], -2)
    linear = (turn @ lean) * scale[:, None, None]
    where = np.column_stack([rng.uniform(-side / 2, side / 2, (count, 2)), zero])
    placed = np.concatenate([linear, where[:, :, None]], axis=2)
    transforms = np.concatenate([np.eye(3, 4)[None], placed]).astype(np.float32)
    materials = [Material((0.85, 0.85, 0.8)), Material((0.35, 0.4, 0.35)), Material((0.85, 0.35, 0.2))]
    materials.append(Material((0.6, 0.55, 0.5), reflective=0.2))
    return Scene(
        triangles=floor,
        tri_material=floor_mat,
        materials=materials,
        meshes=[knot, rock],
        mesh_tri_material=[np.full(len(knot), 2, np.int32), np.full(len(rock), 3, np.int32)],
        instance_mesh=np.concatenate([[0], mesh]).astype(np.int32),
        instance_transforms=transforms,
        camera=Camera((-side * 0.35, -side * 0.5, side * 0.07), (0.0, -side * 0.15, 0.0), fov_y=50.0),
        light=Light((side * 0.3, -side * 0.6, side * 0.5), intensity=1.0),
        sky=(0.55, 0.7, 0.9),
    )
