"""Writes the example study's mesh files (files/, beside study.toml), one per format bvhlab reads
through trimesh, each a scene unlike the bundled ones:

- blobs.ply: an icosphere with 81,920 triangles, its vertices pushed in and out (one dense closed mesh)
- city.glb: 2,500 boxes of random heights on a grid (glTF binary: many small objects on a plane)
- rods.stl: 1,500 long thin cylinders at random angles (long thin objects crossing each other)
- knot.obj: bvhlab's generated torus knot (gen:knot, 250,000 triangles) as a Wavefront OBJ

Deterministic (fixed seeds): the sweep's cell keys hash the files, so a rerun finds its cells."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import trimesh

FILES = Path(__file__).resolve().parent / "files"


def blobs() -> trimesh.Trimesh:
    mesh = trimesh.creation.icosphere(subdivisions=6)
    v = mesh.vertices
    bumps = 1 + 0.25 * np.sin(5 * v[:, 0]) * np.sin(7 * v[:, 1]) * np.sin(3 * v[:, 2] + 1)
    return trimesh.Trimesh(v * bumps[:, None], mesh.faces, process=False)


def city(rng: np.random.Generator) -> trimesh.Trimesh:
    parts = []
    for i in range(50):
        for j in range(50):
            height = rng.gamma(2.0, 1.5)
            box = trimesh.creation.box(extents=(0.8, 0.8, height))
            box.apply_translation((i, j, height / 2))
            parts.append(box)
    return trimesh.util.concatenate(parts)


def rods(rng: np.random.Generator) -> trimesh.Trimesh:
    parts = []
    for _ in range(1500):
        rod = trimesh.creation.cylinder(radius=0.02, height=rng.uniform(2, 8), sections=8)
        rod.apply_transform(trimesh.transformations.random_rotation_matrix(rng.random(3)))
        rod.apply_translation(rng.uniform(-5, 5, 3))
        parts.append(rod)
    return trimesh.util.concatenate(parts)


def knot() -> trimesh.Trimesh:
    from bvhlab.library import load_scene

    scene, _ = load_scene("gen:knot")
    triangles = np.asarray(scene.triangles, dtype=np.float64).reshape(-1, 3)
    return trimesh.Trimesh(triangles, np.arange(len(triangles)).reshape(-1, 3), process=False)


def main() -> int:
    FILES.mkdir(exist_ok=True)
    rng = np.random.default_rng(7)
    for name, make in (("blobs.ply", blobs), ("city.glb", lambda: city(rng)), ("rods.stl", lambda: rods(rng)),
                       ("knot.obj", knot)):  # fmt: skip
        path = FILES / name
        if not path.exists():
            mesh = make()
            tmp = path.with_suffix(path.suffix + ".tmp")
            mesh.export(tmp, file_type=path.suffix[1:])
            tmp.replace(path)
            print(f"wrote {path} ({len(mesh.faces):,} triangles)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
