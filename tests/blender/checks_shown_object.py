"""What an export reads of each instance the depsgraph shows (scope.shown_object): the instanced
object itself where the instance is a copy of it, `instance.object` where it may not be. Blender
leaks a Python wrapper on every read of `DepsgraphObjectInstance.object` for an instance, so the
export reads it only where it must; these checks hold the shortcut to what `instance.object` says
for instances of every kind, and measure the leak it avoids, under each Blender."""

from __future__ import annotations

import gc
import os

import bpy
import harness

from bvhlab.blender.scope import instances_in_scope, shown_object


def _nodes_scatter(name: str, instanced, as_instance: bool, count: int = 3):
    """A mesh object whose geometry nodes put `instanced` on a count × count grid's points (Object
    Info: "As Instance" as given), and keep the grid's own faces beside them."""
    tree = bpy.data.node_groups.new(name, "GeometryNodeTree")
    tree.interface.new_socket("Geometry", in_out="OUTPUT", socket_type="NodeSocketGeometry")
    output = tree.nodes.new("NodeGroupOutput")
    grid = tree.nodes.new("GeometryNodeMeshGrid")
    grid.inputs["Vertices X"].default_value = grid.inputs["Vertices Y"].default_value = count
    info = tree.nodes.new("GeometryNodeObjectInfo")
    info.inputs["Object"].default_value = instanced
    info.inputs["As Instance"].default_value = as_instance
    on_points = tree.nodes.new("GeometryNodeInstanceOnPoints")
    join = tree.nodes.new("GeometryNodeJoinGeometry")
    tree.links.new(grid.outputs["Mesh"], on_points.inputs["Points"])
    tree.links.new(info.outputs["Geometry"], on_points.inputs["Instance"])
    tree.links.new(on_points.outputs["Instances"], join.inputs[0])
    tree.links.new(grid.outputs["Mesh"], join.inputs[0])
    tree.links.new(join.outputs[0], output.inputs[0])
    obj = bpy.data.objects.new(name, bpy.data.meshes.new(name))
    obj.modifiers.new(name, "NODES").node_group = tree
    return obj


def _every_kind_scene():
    """Instances of every kind: a collection (a mesh with a material, a text, a bevelled curve, a
    metaball, a light, a geometry-nodes object whose output is a mesh and instances) instanced by two
    empties; a mesh instanced by vertices; geometry nodes instancing a plain mesh as an object and as
    geometry, and a geometry-nodes object as an object."""
    harness.empty_scene((32, 24))
    harness.add_camera((0, -12, 7), (0, 0, 0))
    scene = bpy.context.scene
    source = bpy.data.collections.new("Source")
    box = harness.add_box("Box", (0.0, 0.0, 0.5), size=0.5)
    box.data.materials.append(bpy.data.materials.new("Red"))
    made = [box]
    for add in (
        bpy.ops.object.text_add,
        bpy.ops.curve.primitive_bezier_circle_add,
        bpy.ops.object.metaball_add,
        lambda: bpy.ops.object.light_add(type="POINT"),
    ):
        add()
        made.append(bpy.context.active_object)
    made[2].data.bevel_depth = 0.1
    plain = harness.add_box("Plain", (0.0, 0.0, 0.0), size=0.2)
    made.append(_nodes_scatter("Nested scatter", plain, as_instance=False, count=2))
    for obj in made:
        for collection in list(obj.users_collection):
            collection.objects.unlink(obj)
        source.objects.link(obj)
    for i in range(2):
        empty = bpy.data.objects.new(f"Instancer {i}", None)
        empty.instance_type, empty.instance_collection = "COLLECTION", source
        empty.location = (4.0 * i - 2.0, 0.0, 0.0)
        scene.collection.objects.link(empty)
    points = bpy.data.meshes.new("Points")
    points.from_pydata([(-3.0, 3.0, 0.0), (3.0, 3.0, 1.0)], [], [])
    by_vertices = bpy.data.objects.new("By vertices", points)
    by_vertices.instance_type = "VERTS"
    scene.collection.objects.link(by_vertices)
    child = harness.add_box("Vertex child", (0.0, 0.0, 0.0), size=0.3)
    child.parent = by_vertices
    scatters = (
        _nodes_scatter("As objects", plain, as_instance=True),
        _nodes_scatter("As geometry", plain, as_instance=False),
        _nodes_scatter("Of a nodes object", made[-1], as_instance=True),
    )
    for z, obj in enumerate(scatters):
        obj.location = (0.0, -3.0, 2.0 * z)
        scene.collection.objects.link(obj)
    bpy.context.view_layer.update()


def _pointer(data) -> int:
    return 0 if data is None else data.as_pointer()


def _what(obj) -> tuple:
    """What an export and the render's notes read of an object shown: its type, data, original,
    material slots and the flags the notes ask."""
    slots = tuple(_pointer(slot.material) for slot in obj.material_slots)
    return (obj.type, _pointer(obj.data), obj.original.name_full, slots, obj.is_shadow_catcher, len(obj.modifiers))


def check_instances_are_read_as_blender_shows_them() -> None:
    """For every instance of every kind, what shown_object gives is what `instance.object` says (its
    type, data, original, material slots); the copies are taken for the instances of plain objects
    and `instance.object` read for what geometry nodes instance as geometry, and for what a text,
    curve or metaball shows (a mesh that is not the object's). Blender hands back the instanced
    object's own wrapper for an instance once that object has one (the temporary copy is made from
    it, its Python instance with it: a review's finding), so only the instances `instance.object`
    shows as the temporary copy itself compare two readings; those are counted by kind."""
    _every_kind_scene()
    depsgraph = bpy.context.evaluated_depsgraph_get()
    copies: dict = {}
    kinds: dict[tuple, int] = {}
    for instance in depsgraph.object_instances:
        if not instance.is_instance:
            continue
        said = instance.object  # what Blender says, read before shown_object wraps the object instanced
        want = _what(said)
        source = instance.instance_object.as_pointer()
        shown = shown_object(instance, copies)
        assert _what(shown) == want, (instance.instance_object.name, _what(shown), want)
        if said.as_pointer() != source:  # the temporary copy: a comparison of two readings
            copied = shown.as_pointer() == source
            kinds[(want[0], copied)] = kinds.get((want[0], copied), 0) + 1
    # the kinds the scene must have given: copies of meshes and lights, and meshes read anew (the
    # geometry instanced as geometry, a text's, curve's and metaball's surfaces)
    assert kinds.get(("MESH", True), 0) >= 3, kinds
    assert kinds.get(("LIGHT", True), 0) >= 1, kinds
    assert kinds.get(("MESH", False), 0) >= 9 + 2 * 3, kinds
    keys = [entry.key for entry in instances_in_scope(depsgraph, bpy.context.view_layer, "visible")]
    assert len(keys) == len(set(keys)), "two instances under one key"


def _resident_mib() -> float:
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 2**20


def check_walks_of_instances_leak_nothing() -> None:
    """Walking 40,000 instances of a plain mesh (geometry nodes' "As Instance") again and again does
    not grow the process: each read of `instance.object` leaked Blender's wrapper of its temporary
    object (62 bytes a read in bpy 4.2, 124 in 5.0: 2.5-5 MB a walk here)."""
    harness.empty_scene((32, 24))
    plain = harness.add_box("Plain", (0.0, 0.0, 0.0), size=0.05)
    plain.hide_set(True)
    scatter = _nodes_scatter("Scatter", plain, as_instance=True, count=200)
    bpy.context.scene.collection.objects.link(scatter)
    bpy.context.view_layer.update()
    depsgraph = bpy.context.evaluated_depsgraph_get()
    layer = bpy.context.view_layer

    def walk() -> int:
        return sum(1 for _ in instances_in_scope(depsgraph, layer, "visible", frozenset({"MESH"})))

    assert walk() == 200 * 200 + 1  # the instances and the grid's faces
    walk()
    gc.collect()
    before = _resident_mib()
    for _ in range(8):
        walk()
    gc.collect()
    grown = _resident_mib() - before
    assert grown < 4.0, f"eight walks of 40,000 instances grew the process by {grown:.1f} MiB"
