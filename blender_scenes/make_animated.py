"""The two animated scenes of `bvhlab animate` (issue 34), made with bpy (no Blender binary):

- wave_anim.blend: the `wave` animation (bvhlab.library.animations.wave: a 354 × 354-quad grid,
  250,632 triangles, a travelling wave and a bump sweeping across) as a geometry-nodes modifier
  reading the scene's frame: the mesh deforms in Blender, nothing is baked;
- crowd_anim.blend: the bundled atrium with 300 knots (480 triangles each) flying down its nave
  (animations.atrium_crowd): geometry-nodes instances of one knot mesh on points whose paths
  come from per-point attributes (radius, height, phase, speed) and the frame, so the exporter
  reads one shared mesh and 300 instances each frame.

Frames 1..ANIMATION_FRAMES (24) are phases t = 0..1 (animations.frame_phase). The node trees
compute in float32 what the library computes in float64: tests/python/test_animate_blend.py
compares exported frames with it. Each file is about 0.1 MB (the geometry is made when Blender
evaluates it), so `make demo` makes them into out/ rather than the repository bundling them:

    .venv/bin/python blender_scenes/make_animated.py --out DIR [--only wave crowd]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import bpy
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import scene_kit as kit  # noqa: E402  (beside this script)

from bvhlab.library.animations import ANIMATION_FRAMES, atrium_crowd, crowd_knot  # noqa: E402

HERE = Path(__file__).resolve().parent


class Nodes:
    """A geometry-nodes modifier on `obj` and terse helpers to wire its tree."""

    def __init__(self, obj, name: str):
        self.tree = bpy.data.node_groups.new(name, "GeometryNodeTree")
        self.tree.interface.new_socket("Geometry", in_out="INPUT", socket_type="NodeSocketGeometry")
        self.tree.interface.new_socket("Geometry", in_out="OUTPUT", socket_type="NodeSocketGeometry")
        self.input = self.tree.nodes.new("NodeGroupInput").outputs[0]
        self.output = self.tree.nodes.new("NodeGroupOutput").inputs[0]
        obj.modifiers.new(name, "NODES").node_group = self.tree

    def node(self, kind: str, inputs: dict | None = None, **props):
        n = self.tree.nodes.new(kind)
        for key, value in props.items():
            setattr(n, key, value)
        for key, value in (inputs or {}).items():
            self.set(n.inputs[key], value)
        return n

    def set(self, socket, value) -> None:
        if isinstance(value, bpy.types.NodeSocket):
            self.tree.links.new(value, socket)
        else:
            socket.default_value = value

    def math(self, op: str, a, b=None):
        n = self.node("ShaderNodeMath", operation=op)
        self.set(n.inputs[0], a)
        if b is not None:
            self.set(n.inputs[1], b)
        return n.outputs[0]

    def phase(self):
        """t = (frame - 1) / (ANIMATION_FRAMES - 1): animations.frame_phase."""
        frame = self.node("GeometryNodeInputSceneTime").outputs["Frame"]
        return self.math("DIVIDE", self.math("SUBTRACT", frame, 1.0), float(ANIMATION_FRAMES - 1))

    def xyz(self, vector):
        return self.node("ShaderNodeSeparateXYZ", {0: vector}).outputs

    def vector(self, x, y, z):
        return self.node("ShaderNodeCombineXYZ", {0: x, 1: y, 2: z}).outputs[0]

    def attribute(self, name: str):
        return self.node("GeometryNodeInputNamedAttribute", {"Name": name}, data_type="FLOAT").outputs["Attribute"]


def _frames(scene) -> None:
    scene.frame_start, scene.frame_end = 1, ANIMATION_FRAMES
    scene.frame_set(1)


def wave(size: int = 354):
    """animations.wave(size): z = 0.03 sin(20x + 6t) + 0.4 exp(-((x - (0.1 + 0.8t))² + (y - 0.5)²) / 0.005)
    over the unit square; Blender's triangulation of the grid's quads (the exporter's loop
    triangles) splits each along the diagonal the library does. (A Triangulate node would make
    that explicit, but through BMesh it took 3 s a frame.)"""
    scene = kit.reset(sky=(0.55, 0.65, 0.8))
    obj = kit.mesh_object("Wave", [], [], [kit.material("Cloth", (0.7, 0.25, 0.2), roughness=0.7)])
    g = Nodes(obj, "Wave motion")
    grid = g.node(
        "GeometryNodeMeshGrid", {"Size X": 1.0, "Size Y": 1.0, "Vertices X": size + 1, "Vertices Y": size + 1}
    )
    x0, y0, _ = g.xyz(g.node("GeometryNodeInputPosition").outputs[0])
    x, y, t = g.math("ADD", x0, 0.5), g.math("ADD", y0, 0.5), g.phase()
    ripple = g.math(
        "MULTIPLY", g.math("SINE", g.math("ADD", g.math("MULTIPLY", x, 20.0), g.math("MULTIPLY", t, 6.0))), 0.03
    )
    dx = g.math("SUBTRACT", x, g.math("ADD", g.math("MULTIPLY", t, 0.8), 0.1))
    dy = g.math("SUBTRACT", y, 0.5)
    r2 = g.math("ADD", g.math("MULTIPLY", dx, dx), g.math("MULTIPLY", dy, dy))
    bump = g.math("MULTIPLY", g.math("EXPONENT", g.math("DIVIDE", r2, -0.005)), 0.4)
    moved = g.node(
        "GeometryNodeSetPosition",
        {"Geometry": grid.outputs["Mesh"], "Position": g.vector(x, y, g.math("ADD", ripple, bump))},
    )
    material = g.node("GeometryNodeSetMaterial", {"Geometry": moved.outputs[0], "Material": obj.data.materials[0]})
    g.set(g.output, material.outputs[0])
    kit.camera((0.1, -0.75, 0.85), (0.5, 0.5, 0.05), lens=30)
    kit.point_light((0.3, -0.2, 1.5), 150)
    _frames(scene)
    return scene


def crowd(count: int = 300, knot_triangles: int = 480):
    """The bundled atrium and animations.atrium_crowd(count): knots instanced on points by geometry
    nodes, each at CrowdPaths.centres(t), turned about z by its angle."""
    bpy.ops.wm.open_mainfile(filepath=str(HERE / "atrium.blend"), load_ui=False)
    scene = bpy.context.scene
    paths = atrium_crowd(count)
    knot = crowd_knot(knot_triangles).astype(np.float32).reshape(-1, 3)
    parts = bpy.data.collections.new("Crowd parts")  # the knot itself is not in the view layer
    scene.collection.children.link(parts)
    mesh = bpy.data.meshes.new("Knot")
    mesh.from_pydata(knot.tolist(), [], [(3 * i, 3 * i + 1, 3 * i + 2) for i in range(len(knot) // 3)])
    mesh.materials.append(kit.material("Knot", (0.85, 0.65, 0.2), metallic=0.3))
    source = bpy.data.objects.new("Knot", mesh)
    parts.objects.link(source)
    bpy.context.view_layer.layer_collection.children[parts.name].exclude = True
    points = bpy.data.meshes.new("Crowd paths")
    points.vertices.add(count)
    for name in ("radius", "height", "phase", "speed"):
        points.attributes.new(name, "FLOAT", "POINT").data.foreach_set("value", getattr(paths, name).astype(np.float32))
    obj = kit.link(bpy.data.objects.new("Crowd", points))
    g = Nodes(obj, "Crowd motion")
    radius, height, phase, speed = (g.attribute(n) for n in ("radius", "height", "phase", "speed"))
    angle = g.math("ADD", phase, g.math("MULTIPLY", g.math("MULTIPLY", speed, 2 * np.pi), g.phase()))
    r = g.math("MULTIPLY", radius, 1.0)
    centre = g.vector(
        g.math("MULTIPLY", g.math("MULTIPLY", r, paths.ax), g.math("COSINE", angle)),
        g.math("MULTIPLY", g.math("MULTIPLY", r, paths.ay), g.math("SINE", angle)),
        g.math("ADD", height, g.math("MULTIPLY", g.math("SINE", g.math("MULTIPLY", angle, 3.0)), 0.8)),
    )
    placed = g.node("GeometryNodeSetPosition", {"Geometry": g.input, "Position": centre})
    info = g.node("GeometryNodeObjectInfo", {"Object": source}, transform_space="ORIGINAL")
    instanced = g.node(
        "GeometryNodeInstanceOnPoints",
        {"Points": placed.outputs[0], "Instance": info.outputs["Geometry"], "Rotation": g.vector(0.0, 0.0, angle)},
    )
    g.set(g.output, instanced.outputs[0])
    _frames(scene)
    return scene


SCENES = {"wave": wave, "crowd": crowd}


def make(name: str, out: Path) -> Path:
    SCENES[name]()
    out.mkdir(parents=True, exist_ok=True)
    path = out / f"{name}_anim.blend"
    kit.save(path)
    print(f"{path}: {path.stat().st_size / 1e6:.2f} MB")
    return path


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", type=Path, required=True)
    ap.add_argument("--only", nargs="*", choices=sorted(SCENES), help="scenes to make (default: both)")
    args = ap.parse_args(argv)
    for name in args.only or SCENES:
        make(name, args.out)


if __name__ == "__main__":
    main()
