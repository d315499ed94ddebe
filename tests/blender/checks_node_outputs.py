"""What a mesh object's geometry nodes put out beside its mesh: a curve (no surface; the depsgraph
shows it as an instance of type CURVE whose to_mesh() is None) and points (an instance of type
POINTCLOUD of the same object). The curve crashed every export (AttributeError in the mesh
reader: Build cancelled, F12 failed with no image); the points were left out without the note a
point cloud object gets (only the first instance of each object was looked at). Now the export
reads the mesh and renders as Cycles does (Cycles renders nothing of such a curve: its Depth pass
is compared), and F12 says the points are not rendered."""

from __future__ import annotations

import bpy
from checks_cameras import camera_scene, compare_depth, cycles_depth, engine_depth
from checks_engine import _last_final

from bvhlab.blender import export_scene


def _nodes(name: str, make) -> bpy.types.NodeTree:
    """A geometry node group joining the input geometry with what make(tree) puts out."""
    tree = bpy.data.node_groups.new(name, "GeometryNodeTree")
    tree.interface.new_socket("Geometry", in_out="INPUT", socket_type="NodeSocketGeometry")
    tree.interface.new_socket("Geometry", in_out="OUTPUT", socket_type="NodeSocketGeometry")
    given, out = tree.nodes.new("NodeGroupInput"), tree.nodes.new("NodeGroupOutput")
    join = tree.nodes.new("GeometryNodeJoinGeometry")
    tree.links.new(given.outputs[0], join.inputs[0])
    tree.links.new(make(tree), join.inputs[0])
    tree.links.new(join.outputs[0], out.inputs[0])
    return tree


def _curve_line(tree):
    line = tree.nodes.new("GeometryNodeCurvePrimitiveLine")
    line.inputs["End"].default_value = (3.0, 0.0, 1.0)
    return line.outputs[0]


def _points(tree):
    points = tree.nodes.new("GeometryNodeMeshToPoints")
    grid = tree.nodes.new("GeometryNodeMeshGrid")
    tree.links.new(grid.outputs[0], points.inputs["Mesh"])
    return points.outputs[0]


def check_node_curves_and_points_beside_a_mesh(tmp_dir) -> None:
    scene = camera_scene()
    host = bpy.data.objects["Box A"]
    triangles = len(export_scene(bpy.context).flattened().triangles)
    host.modifiers.new("Curve", "NODES").node_group = _nodes("Line", _curve_line)
    bpy.context.view_layer.update()
    kinds = {(i.object.type, i.object.original.name) for i in bpy.context.evaluated_depsgraph_get().object_instances}
    assert ("CURVE", "Box A") in kinds, kinds  # the case: a curve instance of the mesh object
    assert len(export_scene(bpy.context).flattened().triangles) == triangles  # the mesh; the curve has no surface
    assert bpy.ops.bvhlab.build() == {"FINISHED"}
    line = compare_depth(engine_depth(tmp_dir, "curve", "cpu"), cycles_depth(tmp_dir, "curve"), "a node curve")
    print(line)
    assert _last_final(scene)["unrendered"] == [], _last_final(scene)["unrendered"]
    host.modifiers.new("Points", "NODES").node_group = _nodes("Points", _points)
    bpy.context.view_layer.update()
    engine_depth(tmp_dir, "points", "cpu")
    assert _last_final(scene)["unrendered"] == ["point clouds are not rendered (object 'Box A')"], _last_final(scene)
