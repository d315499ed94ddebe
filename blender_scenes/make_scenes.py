"""Generate the bundled .blend scenes and scenes.json (bpy as a Python module, no Blender binary):

    .venv/bin/python blender_scenes/make_scenes.py [--out blender_scenes] [--only NAME ...]

Geometry comes from modifiers (subdivision, arrays, mirror, bevel, wave), so the files stay small
and the triangle counts are those of the evaluated scene. Deterministic: seeded, no timestamps
in the data. scenes.json records, per scene, the counts Blender itself evaluates (loop triangles
of visible meshes, flagged spheres), the materials as bvhlab should read them, and a few world
positions the export must reproduce; the tests compare the export against it.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import bpy
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import scene_kit as kit  # noqa: E402  (beside this script)


def five_spheres():
    """Report Figures 3-4: five spheres in a row where the median split (2 | 3) differs from the
    mean and SAH splits (3 | 2) at the root."""
    scene = kit.reset(sky=(0.6, 0.72, 0.85))
    colors = [(0.8, 0.2, 0.2), (0.9, 0.6, 0.1), (0.9, 0.85, 0.2), (0.2, 0.7, 0.3), (0.2, 0.4, 0.85)]
    spheres = [
        (-4.0, 0.0, 1.0, 0.6),
        (-2.9, 0.4, 1.2, 0.5),
        (-1.9, -0.3, 0.9, 0.7),
        (3.0, 0.2, 1.1, 0.55),
        (4.1, -0.2, 0.95, 0.65),
    ]
    for i, ((x, y, z, r), color) in enumerate(zip(spheres, colors)):
        kit.uv_sphere(f"Sphere {i + 1}", (x, y, z), r, kit.material(f"Sphere {i + 1}", color))
    kit.camera((0.0, -11.0, 3.5), (0.0, 0.0, 1.0), lens=40)
    kit.point_light((1.0, -5.0, 8.0), 1500)
    return scene, {"spheres": spheres}


def random_spheres(count=1000, half=4.0, seed=42):
    """Report §4.2: spheres placed uniformly at random in a cube (linked duplicates of one mesh)."""
    scene = kit.reset(sky=(0.5, 0.6, 0.75))
    rng = np.random.default_rng(seed)
    centres = rng.uniform(-half, half, (count, 3)).round(4)
    radii = rng.uniform(0.1, 0.22, count).round(4)
    palette = [
        kit.material(f"Random {k}", c)
        for k, c in enumerate(
            [(0.85, 0.3, 0.25), (0.3, 0.6, 0.85), (0.9, 0.8, 0.3), (0.4, 0.75, 0.4), (0.75, 0.5, 0.8)]
        )
    ]
    mesh = None
    for i in range(count):
        obj = kit.uv_sphere(
            f"Random sphere {i:04d}", centres[i], radii[i], palette[i % len(palette)], segments=16, rings=8, mesh=mesh
        )
        mesh = obj.data
    kit.camera((10.0, -14.0, 9.0), (0.0, 0.0, 0.0), lens=40)
    kit.point_light((6.0, -8.0, 10.0), 4000)
    return scene, {"spheres": [[*c, r] for c, r in zip(centres[:5].tolist(), radii[:5].tolist())]}


def suzanne(levels):
    """A high-poly model: Suzanne with a Subdivision Surface modifier (level 4 ≈ 250k triangles,
    level 5 ≈ 1M), moved, turned and scaled so the export must apply the world transform."""
    scene = kit.reset(sky=(0.45, 0.55, 0.7))
    bpy.ops.mesh.primitive_monkey_add(location=(0.5, 0.0, 1.2), rotation=(0.0, 0.0, 0.5), scale=(1.5,) * 3)
    monkey = bpy.context.object
    monkey.name = "Suzanne"
    monkey.data.materials.append(kit.material("Clay", (0.8, 0.45, 0.3), roughness=0.6))
    kit.subdivide(monkey, levels)
    kit.box("Floor", (-6, -6, -0.2), (6, 6, 0.0), [kit.material("Floor", (0.6, 0.6, 0.6))])
    kit.camera((0.0, -7.5, 3.0), (0.3, 0.0, 1.2), lens=45)
    kit.point_light((-3.0, -4.0, 6.0), 1200)
    return scene, {"points": [[-6, -6, 0], [6, 6, -0.2]]}


def _atrium_colonnade(mirrored, marble, stone):
    """The atrium's columns with their bases and capitals, and the arches between them."""
    bpy.ops.mesh.primitive_cylinder_add(vertices=32, radius=0.3, depth=5.6, location=(-10.5, -3.5, 3.1))
    column = bpy.context.object
    column.name = "Column"
    column.data.materials.append(marble)
    kit.modifier(column, "BEVEL", width=0.05, segments=3)
    mirrored(column, (8, (3.0, 0.0, 0.0)))
    for name, z0, z1 in (("Base", 0.0, 0.3), ("Capital", 5.9, 6.2)):
        part = kit.box(name, (-10.95, -3.95, z0), (-10.05, -3.05, z1), [stone])
        kit.modifier(part, "BEVEL", width=0.03, segments=2)
        mirrored(part, (8, (3.0, 0.0, 0.0)))
    arch = kit.arch("Arch", 1.05, 1.5, 0.8, 24, [stone])
    arch.location = (-9.0, -3.5, 6.2)
    kit.subdivide(arch, 1, simple=True)
    mirrored(arch, (7, (3.0, 0.0, 0.0)))


def _atrium_cloth(mirrored, cloth, curtain):
    """The atrium's hanging cloth: a banner between each pair of columns, and a curtain."""
    banner = kit.mesh_object(
        "Banner",
        [(-0.7, -2.0, 0), (0.7, -2.0, 0), (0.7, 2.0, 0), (-0.7, 2.0, 0)],
        [(0, 1, 2, 3)],
        [cloth],
        location=(-9.0, -2.4, 5.4),
    )
    banner.rotation_euler = (np.pi / 2, 0.0, 0.0)
    kit.subdivide(banner, 6, simple=True)
    kit.modifier(banner, "WAVE", use_x=True, use_y=False, height=0.08, width=0.35, narrowness=1.0, speed=0.0)
    mirrored(banner, (7, (3.0, 0.0, 0.0)))
    drape = kit.mesh_object(
        "Curtain",
        [(-4.0, -3.0, 0), (4.0, -3.0, 0), (4.0, 3.0, 0), (-4.0, 3.0, 0)],
        [(0, 1, 2, 3)],
        [curtain],
        location=(11.6, 0.0, 4.2),
    )
    drape.rotation_euler = (np.pi / 2, 0.0, np.pi / 2)
    kit.subdivide(drape, 8, simple=True)
    kit.modifier(drape, "WAVE", use_x=True, use_y=False, height=0.15, width=0.6, narrowness=1.5, speed=0.0)


def atrium():
    """The Sponza role of the report's Table 1: an atrium with columns, arches, floor tiles, walls
    and hanging cloth, triangles from metres (walls) to millimetres (cloth) across."""
    scene = kit.reset(sky=(0.7, 0.8, 0.95))
    stone, marble = kit.material("Stone", (0.75, 0.7, 0.6)), kit.material("Marble", (0.9, 0.88, 0.85), roughness=0.2)
    tile, cloth = kit.material("Tile", (0.55, 0.35, 0.25)), kit.material("Cloth", (0.7, 0.1, 0.12), roughness=0.8)
    curtain = kit.material("Curtain", (0.15, 0.25, 0.6), roughness=0.8)
    centre = kit.link(bpy.data.objects.new("Atrium centre", None))  # the mirror plane y = 0

    def mirrored(obj, along_x=None):
        if along_x:
            kit.array(obj, *along_x)
        kit.modifier(obj, "MIRROR", use_axis=(False, True, False), mirror_object=centre)
        return obj

    floor = kit.box("Floor tile", (-12.0, -5.0, -0.06), (-11.02, -4.02, 0.0), [tile])
    kit.modifier(floor, "BEVEL", width=0.015, segments=2)
    kit.array(floor, 24, (1.0, 0.0, 0.0))
    kit.array(floor, 10, (0.0, 1.0, 0.0))
    _atrium_colonnade(mirrored, marble, stone)
    mirrored(kit.box("Gallery", (-12.0, 2.6, 7.7), (12.0, 5.0, 8.0), [stone]))
    mirrored(kit.box("Wall", (-12.0, 5.0, 0.0), (12.0, 5.3, 10.0), [stone]))
    kit.box("End wall", (12.0, -5.3, 0.0), (12.3, 5.3, 10.0), [stone])
    _atrium_cloth(mirrored, cloth, curtain)
    kit.camera((-11.0, -1.5, 2.2), (4.0, 0.8, 4.0), lens=22)
    kit.point_light((0.0, 0.0, 7.0), 6000, color=(1.0, 0.92, 0.8))
    return scene, {"points": [[12.3, 5.3, 10.0], [-12.0, -5.3, 0.0]]}


def whitted():
    """Whitted (1980): a mirror sphere and a glass sphere over a checkerboard, plus a matte mesh ball."""
    scene = kit.reset(sky=(0.35, 0.55, 0.85))
    red, yellow = kit.material("Check red", (0.8, 0.1, 0.08)), kit.material("Check yellow", (0.9, 0.8, 0.1))
    bpy.ops.mesh.primitive_grid_add(x_subdivisions=16, y_subdivisions=16, size=10.0)
    floor = bpy.context.object
    floor.name = "Checker floor"
    floor.data.materials.append(red)
    floor.data.materials.append(yellow)
    centres = np.empty(len(floor.data.polygons) * 3, np.float32)
    floor.data.polygons.foreach_get("center", centres)
    cell = 10.0 / round(len(floor.data.polygons) ** 0.5)
    cells = np.floor((centres.reshape(-1, 3)[:, :2] + 5.0) / cell).astype(int)
    floor.data.polygons.foreach_set("material_index", (cells.sum(1) % 2).astype(np.int32))
    kit.uv_sphere(
        "Glass sphere",
        (0.4, 0.0, 1.3),
        1.0,
        kit.material("Glass", (1.0, 1.0, 1.0), transmission=1.0, ior=1.5, roughness=0.0),
    )
    kit.uv_sphere(
        "Mirror sphere", (-1.9, 2.2, 1.1), 1.1, kit.material("Mirror", (0.9, 0.9, 0.9), metallic=1.0, roughness=0.0)
    )
    bpy.ops.mesh.primitive_ico_sphere_add(subdivisions=3, radius=0.8, location=(2.4, 2.0, 0.8))
    ball = bpy.context.object
    ball.name = "Matte ball"
    ball.data.materials.append(kit.material("Blue", (0.15, 0.3, 0.8)))
    kit.camera((0.0, -9.0, 3.2), (0.0, 0.8, 1.0), lens=35)
    kit.point_light((3.0, -4.0, 8.0), 2500)
    return scene, {"points": [[-5, -5, 0], [5, 5, 0]]}


def moving_ball():
    """Frames 1-3 for animation renders: a mesh ball rolls along x and an analytic sphere rises,
    over a floor, seen by a still camera (keyframes with linear interpolation)."""
    scene = kit.reset(sky=(0.5, 0.65, 0.85), resolution=(160, 120))
    scene.frame_start, scene.frame_end = 1, 3
    kit.box("Floor", (-5.0, -5.0, -0.2), (5.0, 5.0, 0.0), [kit.material("Floor", (0.6, 0.6, 0.55))])
    bpy.ops.mesh.primitive_ico_sphere_add(subdivisions=3, radius=0.7, location=(-2.0, 0.0, 0.7))
    ball = bpy.context.object
    ball.name = "Ball"
    ball.data.materials.append(kit.material("Red", (0.8, 0.15, 0.1)))
    kit.animate(ball, "location", {1: (-2.0, 0.0, 0.7), 2: (0.0, 0.0, 0.7), 3: (2.0, 0.0, 0.7)})
    bubble = kit.uv_sphere("Bubble", (0.0, 2.0, 0.6), 0.5, kit.material("Blue", (0.15, 0.3, 0.85)))
    kit.animate(bubble, "location", {1: (0.0, 2.0, 0.6), 2: (0.0, 2.0, 1.2), 3: (0.0, 2.0, 1.8)})
    scene.frame_set(1)
    kit.camera((0.0, -9.0, 3.5), (0.0, 0.5, 0.8), lens=35)
    kit.point_light((2.0, -4.0, 6.0), 1500)
    return scene, {"points": [[-5, -5, 0], [5, 5, -0.2]]}


SCENES = {
    "five_spheres": (
        five_spheres,
        "Five analytic spheres in a row: the report's Figures 3-4, where the median split differs from mean and SAH",
    ),
    "random_spheres": (random_spheres, "1000 analytic spheres uniformly at random in a cube (report §4.2)"),
    "suzanne_250k": (lambda: suzanne(4), "Suzanne, Subdivision Surface level 4, on a floor"),
    "suzanne_1m": (lambda: suzanne(5), "Suzanne, Subdivision Surface level 5, on a floor"),
    "atrium": (
        atrium,
        "An atrium with columns, arches, floor tiles and hanging cloth (the Sponza role of the report's Table 1)",
    ),
    "whitted": (whitted, "Reflective and transparent spheres over a checkerboard (Whitted 1980)"),
    "moving_ball": (
        moving_ball,
        "Frames 1-3: a mesh ball and an analytic sphere move over a floor (animation renders)",
    ),
}


def make(name: str, out: Path) -> dict:
    builder, description = SCENES[name]
    scene, positions = builder()
    triangles, spheres = kit.counts(scene)
    path = out / f"{name}.blend"
    entry = {
        "file": path.name,
        "description": description,
        "triangles": triangles,
        "spheres": spheres,
        "materials": kit.material_rows(scene),
        "world_positions": positions,
    }
    kit.save(path)
    print(f"{path}: {triangles} triangles, {spheres} spheres, {path.stat().st_size / 1e6:.2f} MB")
    return entry


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", type=Path, default=Path(__file__).resolve().parent)
    ap.add_argument("--only", nargs="*", choices=sorted(SCENES), help="scenes to remake (default: all)")
    args = ap.parse_args(argv)
    index_path = args.out / "scenes.json"
    index = json.loads(index_path.read_text()) if index_path.exists() else {}
    for name in args.only or SCENES:
        index[name] = make(name, args.out)
    index_path.write_text(json.dumps({k: index[k] for k in SCENES if k in index}, indent=1) + "\n")


if __name__ == "__main__":
    main()
