"""Blender scenes with instancing of every kind (collection instances, linked duplicates, geometry
nodes, nested collections, instancing by vertices and faces), made with bpy for the tests of the
instanced export (test_export_instances.py), the add-on's instancing tests and the benches."""

import blender_checks  # noqa: F401  (import path for the shared checks)
import bpy  # noqa: E402  (after harness)
import harness  # before bpy

from bvhlab.blender.compat import ensure_shader_tree  # noqa: E402

#: Transforms with rotation, non-uniform scale and mirroring (negative scale).
PLACES = [
    ((0.0, 0.0, 0.0), (0.0, 0.0, 0.0), (1.0, 1.0, 1.0)),
    ((3.0, 0.5, 0.0), (0.3, 0.0, 0.7), (1.0, 0.5, 1.5)),
    ((-3.0, 0.0, 0.5), (0.0, 0.4, -0.2), (-1.0, 1.0, 1.0)),
    ((0.0, 3.0, -0.5), (1.1, 0.2, 0.0), (0.7, -1.2, 0.9)),
]


def _material(name, color):
    material = bpy.data.materials.new(name)
    ensure_shader_tree(material)
    material.node_tree.nodes["Principled BSDF"].inputs["Base Color"].default_value = (*color, 1.0)
    return material


def suzanne(name="Monkey", subdivisions=0):
    """Suzanne (968 triangles; 15,744 with two subdivisions applied), not in the scene."""
    bpy.ops.mesh.primitive_monkey_add()
    obj = bpy.context.active_object
    if subdivisions:
        obj.modifiers.new("Subdivision", "SUBSURF").levels = subdivisions
        bpy.context.view_layer.update()
        mesh = bpy.data.meshes.new_from_object(obj.evaluated_get(bpy.context.evaluated_depsgraph_get()))
        old = obj.data
        obj.modifiers.clear()
        obj.data = mesh
        bpy.data.meshes.remove(old)
    obj.name = obj.data.name = name
    bpy.context.scene.collection.objects.unlink(obj)
    return obj


def _place(obj, place):
    obj.location, obj.rotation_euler, obj.scale = place


def base_scene(resolution=(64, 48)):
    scene = harness.empty_scene(resolution)
    harness.add_camera((0.5, -12.0, 5.0), (0.0, 0.5, 0.0), lens=30)
    harness.add_point_light((3.0, -5.0, 6.0))
    return scene


def collection_instances_scene():
    """A collection (Suzanne with a material, a box) instanced by four empties placed by PLACES,
    and a box used once."""
    scene = base_scene()
    source = bpy.data.collections.new("Source")
    monkey = suzanne()
    monkey.data.materials.append(_material("Red", (0.8, 0.1, 0.1)))
    source.objects.link(monkey)
    box = harness.add_box("Inner box", (0.0, 0.0, 1.2), size=0.4)
    scene.collection.objects.unlink(box)
    source.objects.link(box)
    for i, place in enumerate(PLACES):
        empty = bpy.data.objects.new(f"Instance {i}", None)
        empty.instance_type, empty.instance_collection = "COLLECTION", source
        scene.collection.objects.link(empty)
        _place(empty, place)
    harness.add_box("Floor", (0.0, 0.0, -1.5), size=1.0, scale=(8.0, 8.0, 0.2))
    bpy.context.view_layer.update()
    return scene


def linked_duplicates_scene():
    """Four objects sharing Suzanne's mesh data (PLACES), one more with an object-level material
    (a mesh of its own), one with a modifier (its own evaluated mesh, used once)."""
    scene = base_scene()
    mesh = suzanne().data
    mesh.materials.append(_material("Grey", (0.6, 0.6, 0.6)))
    for i, place in enumerate(PLACES):
        obj = bpy.data.objects.new(f"Duplicate {i}", mesh)
        scene.collection.objects.link(obj)
        _place(obj, place)
    for name, location in (("Green A", (-2.0, -2.0, 1.5)), ("Green B", (2.0, -2.0, 1.5))):
        obj = bpy.data.objects.new(name, mesh)
        scene.collection.objects.link(obj)
        obj.location, obj.scale = location, (0.5, 0.5, 0.5)
        obj.material_slots[0].link = "OBJECT"
        obj.material_slots[0].material = bpy.data.materials.get("Green") or _material("Green", (0.1, 0.7, 0.1))
    modified = bpy.data.objects.new("Modified", mesh)
    scene.collection.objects.link(modified)
    modified.location = (0.0, -2.0, -1.0)
    modified.modifiers.new("Wave", "SIMPLE_DEFORM").deform_method = "TWIST"
    bpy.context.view_layer.update()
    return scene


def geometry_nodes_scene():
    """Geometry nodes: a 4 × 3 grid → Instance on Points of Suzanne, each with a random rotation and
    the scale (1.0, -0.7, 0.9) (non-uniform, mirroring)."""
    scene = base_scene()
    monkey = suzanne()
    tree = bpy.data.node_groups.new("Scatter", "GeometryNodeTree")
    tree.interface.new_socket("Geometry", in_out="OUTPUT", socket_type="NodeSocketGeometry")
    output = tree.nodes.new("NodeGroupOutput")
    grid = tree.nodes.new("GeometryNodeMeshGrid")
    grid.inputs["Size X"].default_value, grid.inputs["Size Y"].default_value = 8.0, 5.0
    grid.inputs["Vertices X"].default_value, grid.inputs["Vertices Y"].default_value = 4, 3
    info = tree.nodes.new("GeometryNodeObjectInfo")
    info.inputs["Object"].default_value = monkey
    info.inputs["As Instance"].default_value = False
    random = tree.nodes.new("FunctionNodeRandomValue")
    random.data_type = "FLOAT_VECTOR"
    random.inputs["Min"].default_value = (-3.0, -3.0, -3.0)
    random.inputs["Max"].default_value = (3.0, 3.0, 3.0)
    instance = tree.nodes.new("GeometryNodeInstanceOnPoints")
    instance.inputs["Scale"].default_value = (1.0, -0.7, 0.9)
    tree.links.new(grid.outputs["Mesh"], instance.inputs["Points"])
    tree.links.new(info.outputs["Geometry"], instance.inputs["Instance"])
    tree.links.new(random.outputs[0], instance.inputs["Rotation"])
    tree.links.new(instance.outputs["Instances"], output.inputs[0])
    obj = bpy.data.objects.new("Scatter", bpy.data.meshes.new("Scatter"))
    scene.collection.objects.link(obj)
    obj.modifiers.new("Scatter", "NODES").node_group = tree
    bpy.context.view_layer.update()
    return scene


def nested_instances_scene():
    """Suzanne in collection "Leaf", instanced by three rotated and scaled empties in collection
    "Row", which four empties (PLACES: one mirrored) instance: 12 Suzannes, two levels."""
    scene = base_scene()
    leaf = bpy.data.collections.new("Leaf")
    leaf.objects.link(suzanne())
    row = bpy.data.collections.new("Row")
    for i in range(3):
        empty = bpy.data.objects.new(f"Leaf {i}", None)
        empty.instance_type, empty.instance_collection = "COLLECTION", leaf
        row.objects.link(empty)
        _place(empty, ((1.8 * i - 1.8, 0.0, 0.3 * i), (0.0, 0.0, 0.5 * i), (0.8, 0.8 + 0.2 * i, 0.8)))
    for i, place in enumerate(PLACES):
        empty = bpy.data.objects.new(f"Row {i}", None)
        empty.instance_type, empty.instance_collection = "COLLECTION", row
        scene.collection.objects.link(empty)
        _place(empty, place)
    bpy.context.view_layer.update()
    return scene


def vertex_and_face_instances_scene():
    """Instancing by vertices (Suzanne at three loose vertices, rotated by them) and by faces (a box
    on each of two faces of different sizes, scaled by them; the faces render too)."""
    scene = base_scene()
    points = bpy.data.meshes.new("Points")
    points.from_pydata([(-3.0, 0.0, 0.0), (0.0, 1.0, 1.0), (3.0, 0.0, -0.5)], [], [])
    by_vertices = bpy.data.objects.new("By vertices", points)
    scene.collection.objects.link(by_vertices)
    by_vertices.instance_type = "VERTS"
    monkey = suzanne()
    scene.collection.objects.link(monkey)
    monkey.parent = by_vertices
    faces = bpy.data.meshes.new("Faces")
    faces.from_pydata(
        [(-2, 2, -1), (-1, 2, -1), (-1, 3, -1), (-2, 3, -1), (1, 2, -1), (3, 2, -1), (3, 4, -0.5), (1, 4, -0.5)],
        [],
        [(0, 1, 2, 3), (4, 5, 6, 7)],
    )
    by_faces = bpy.data.objects.new("By faces", faces)
    scene.collection.objects.link(by_faces)
    by_faces.instance_type, by_faces.use_instance_faces_scale = "FACES", True
    box = harness.add_box("Face box", (0.0, 0.0, 0.0), size=0.8)
    box.parent = by_faces
    bpy.context.view_layer.update()
    return scene


SCENES = {
    "collection_instances": (collection_instances_scene, 2, 8),
    "linked_duplicates": (linked_duplicates_scene, 2, 6),
    "geometry_nodes": (geometry_nodes_scene, 1, 12),
    "nested_collection_instances": (nested_instances_scene, 1, 12),
    "vertex_and_face_instances": (vertex_and_face_instances_scene, 2, 7),  # 5, and the children themselves
}
