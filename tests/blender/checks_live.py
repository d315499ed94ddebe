"""A LiveScene synced from every depsgraph update, as the Rendered viewport syncs it, against one
that walks the depsgraph at every sync (`place_from_updates=False`): where the updates say only
instances, the camera or the light moved, the sync takes their matrices from the updates alone
(bvhlab/blender/placed_only.py) and must export exactly what the walk exports; anything else must
walk. Under every Blender: what `depsgraph.updates` names for each edit is Blender's, and the
skipped walk is only right where each version names what this expects."""

from __future__ import annotations

import math
import warnings

import bmesh
import bpy
import harness
import numpy as np

from bvhlab.blender import ExportError, LiveScene
from bvhlab.blender.sphere import SPHERE_PROPERTY

#: Linked duplicates of one box: instances of one mesh of the scene.
DUPLICATES = 12


def _scene():
    """A floor used once, DUPLICATES boxes sharing one mesh (the first parented to an empty), a
    box in a collection instanced by an empty, a camera and a light."""
    scene = harness.empty_scene()
    camera = harness.add_camera((0.0, -16.0, 7.0), (0.0, 0.0, 0.0))
    light = harness.add_point_light((2.0, -4.0, 6.0))
    harness.add_box("Floor", (0.0, 0.0, -1.0), scale=(8.0, 8.0, 0.2))
    first = harness.add_box("Dup0", (-5.0, 0.0, 0.0))
    duplicates = [first]
    for i in range(1, DUPLICATES):
        obj = bpy.data.objects.new(f"Dup{i}", first.data)
        scene.collection.objects.link(obj)
        obj.location = (-5.0 + i * 0.9, 0.0, 0.0)
        duplicates.append(obj)
    parent = bpy.data.objects.new("Parent", None)
    scene.collection.objects.link(parent)
    first.parent = parent
    kid = harness.add_box("Kid", (0.0, 0.0, 0.6), size=0.2)  # a mover from its first move on
    kid.parent = duplicates[1]
    inside = bpy.data.collections.new("Inside")
    box = harness.add_box("InC", (0.0, 0.0, 0.0), size=0.5)
    scene.collection.objects.unlink(box)
    inside.objects.link(box)
    instancer = bpy.data.objects.new("Instancer", None)
    instancer.instance_type, instancer.instance_collection = "COLLECTION", inside
    instancer.location = (0.0, 3.0, 1.0)
    scene.collection.objects.link(instancer)
    harness.add_box("Blob", (3.0, -2.0, 0.0), size=0.8)  # edited: a mover from its first edit on
    for name, x in (("Ball", -2.0), ("Marble", 2.0)):  # analytic spheres: mesh 0's, placed by row
        harness.add_box(name, (x, -3.0, 0.5), size=0.6)[SPHERE_PROPERTY] = True
    # a box deformed by an armature's bone, another by a shape key (both animated later)
    rig = bpy.data.objects.new("Rig", bpy.data.armatures.new("Rig"))
    scene.collection.objects.link(rig)
    bpy.context.view_layer.objects.active = rig
    bpy.ops.object.mode_set(mode="EDIT")
    bone = rig.data.edit_bones.new("Bone")
    bone.head, bone.tail = (0.0, 0.0, 0.0), (0.0, 0.0, 1.0)
    bpy.ops.object.mode_set(mode="OBJECT")
    skin = harness.add_box("Skin", (4.5, 0.0, 0.0), size=0.6)
    skin.modifiers.new("Rig", "ARMATURE").object = rig
    skin.vertex_groups.new(name="Bone").add(list(range(len(skin.data.vertices))), 1.0, "REPLACE")
    _sprout()
    held = harness.add_box("Held", (4.0, 3.0, 0.0), size=0.4)  # a mover by its constraint alone
    held.constraints.new("LIMIT_LOCATION")
    morph = harness.add_box("Morph", (-4.5, -2.0, 0.0), size=0.6)
    morph.shape_key_add(name="Basis")
    for point in morph.shape_key_add(name="Up").data:
        point.co.z += 0.5
    bpy.context.view_layer.update()
    return scene, camera, light, duplicates, parent, box, instancer


def _sprout():
    """A box whose geometry-nodes modifier (off for now) instances another box at each vertex."""
    sprout = harness.add_box("Sprout", (-3.0, 3.0, 0.0), size=0.5)
    seed = harness.add_box("Seed", (0.0, 6.0, 0.0), size=0.1)
    tree = bpy.data.node_groups.new("Sprout", "GeometryNodeTree")
    tree.interface.new_socket("Geometry", in_out="INPUT", socket_type="NodeSocketGeometry")
    tree.interface.new_socket("Geometry", in_out="OUTPUT", socket_type="NodeSocketGeometry")
    nodes, links = tree.nodes, tree.links
    given, result = nodes.new("NodeGroupInput"), nodes.new("NodeGroupOutput")
    info = nodes.new("GeometryNodeObjectInfo")
    info.inputs["Object"].default_value = seed
    info.inputs["As Instance"].default_value = True
    on_points, join = nodes.new("GeometryNodeInstanceOnPoints"), nodes.new("GeometryNodeJoinGeometry")
    links.new(given.outputs[0], on_points.inputs["Points"])
    links.new(info.outputs["Geometry"], on_points.inputs["Instance"])
    links.new(given.outputs[0], join.inputs[0])
    links.new(on_points.outputs[0], join.inputs[0])
    links.new(join.outputs[0], result.inputs[0])
    modifier = sprout.modifiers.new("Sprout", "NODES")
    modifier.node_group = tree
    modifier.show_viewport = False


def _same(placed, walked) -> None:
    """The two LiveScenes' scenes, array for array."""
    a, b = placed.scene, walked.scene
    for name in ("triangles", "spheres", "tri_material", "sphere_material", "instance_mesh", "instance_transforms"):
        x, y = getattr(a, name), getattr(b, name)
        assert (x is None) == (y is None) and (x is None or np.array_equal(x, y)), name
    for name in ("meshes", "mesh_tri_material"):
        x, y = getattr(a, name), getattr(b, name)
        assert len(x) == len(y) and all(np.array_equal(p, q) for p, q in zip(x, y)), name
    assert a.materials == b.materials and a.camera == b.camera and a.light == b.light and a.sky == b.sky


#: The report fields a placed sync and a walk must agree on.
FIELDS = ("geometry", "refittable", "placeable", "materials", "objects_read", "objects_moved", "instances_moved")


def check_moves_are_placed_as_the_walk_places_them() -> None:
    scene, camera, light, duplicates, parent, box, instancer = _scene()
    placed, walked = LiveScene("visible"), LiveScene("visible", place_from_updates=False)
    reports: list = []

    def sync(live, depsgraph, scene):
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                return live.sync(depsgraph, scene)
        except ExportError as error:
            return error

    problems: list[str] = []

    def synced(scene, depsgraph):
        mine, theirs = sync(placed, depsgraph, scene), sync(walked, depsgraph, scene)
        reports.append((mine, theirs))
        if isinstance(mine, ExportError) or isinstance(theirs, ExportError):
            return
        try:  # each sync's scenes, as it leaves them (a frame change may be synced twice)
            _same(placed, walked)
            for field in FIELDS:
                assert getattr(mine, field) == getattr(theirs, field), (field, mine, theirs)
        except AssertionError as error:
            problems.append(f"{error!r} after sync {len(reports)}")

    def move(obj, dx=0.0, dz=0.0):
        return lambda: setattr(obj, "location", (obj.location.x + dx, obj.location.y, obj.location.z + dz))

    def scale(obj, s):
        return lambda: setattr(obj, "scale", (s, s, s))

    def both(a, b):
        return lambda: (a(), b())

    def keyframes(obj, path, values):
        def insert():
            for frame, value in values:
                setattr(obj, path, value)
                obj.keyframe_insert(path, frame=frame)

        return insert

    def frame(f):
        return lambda: scene.frame_set(f)

    blob = bpy.data.objects["Blob"]

    def edit(obj, dz=0.05, at=None):
        def move_vertex():
            vertex = obj.data.vertices[0]
            if at is not None:
                vertex.co = at
            vertex.co.z += dz
            obj.data.update()

        return move_vertex

    def edit_mode(enter):
        def switch():
            bpy.context.view_layer.objects.active = blob
            bpy.ops.object.mode_set(mode="EDIT" if enter else "OBJECT")

        return switch

    def edit_in_edit_mode():
        mesh = bmesh.from_edit_mesh(blob.data)
        mesh.verts.ensure_lookup_table()
        mesh.verts[1].co.x += 0.05
        bmesh.update_edit_mesh(blob.data)

    def faces(keep):
        def change():
            mesh = bmesh.new()
            mesh.from_mesh(blob.data)
            if keep:
                bmesh.ops.create_cube(mesh, size=0.8)
            else:
                bmesh.ops.delete(mesh, geom=list(mesh.faces), context="FACES_ONLY")
            mesh.to_mesh(blob.data)
            mesh.free()
            blob.data.update()

        return change

    def subdivide(levels):
        def change():
            modifier = blob.modifiers.get("Subdivision") or blob.modifiers.new("Subdivision", "SUBSURF")
            modifier.levels = levels

        return change

    def bone_keyframes():
        bone = bpy.data.objects["Rig"].pose.bones["Bone"]
        for f, z in ((1, 0.0), (9, 1.5)):
            bone.location = (0.0, 0.0, z)
            bone.keyframe_insert("location", frame=f)

    def shape_keyframes():
        up = bpy.data.objects["Morph"].data.shape_keys.key_blocks["Up"]
        for f, value in ((1, 0.0), (9, 1.0)):
            up.value = value
            up.keyframe_insert("value", frame=f)

    def hide_keyframes():
        morph = bpy.data.objects["Morph"]
        for f, hidden in ((1, False), (5, True)):
            morph.hide_viewport = hidden
            morph.keyframe_insert("hide_viewport", frame=f)

    def sprout(on):
        return lambda: setattr(bpy.data.objects["Sprout"].modifiers["Sprout"], "show_viewport", on)

    def still():
        """A box keyframed once: a mover (animated) that never moves."""
        obj = harness.add_box("Still", (1.0, -3.0, 0.0), size=0.4)
        obj.keyframe_insert("location", frame=1)

    # (what, the edit, whether the sync may skip the walk; None: either, the scenes compared all the
    # same; an object's name: both refuse the scene, naming it)
    steps = [
        ("move a duplicate", move(duplicates[3], dz=0.5), True),
        ("rotate it", lambda: setattr(duplicates[3], "rotation_euler", (0.0, 0.0, 0.7)), True),
        ("move it back", move(duplicates[3], dz=-0.5), True),
        ("move the parent of a duplicate", move(parent, dz=0.75), True),
        ("move two duplicates", both(move(duplicates[5], dx=0.1), move(duplicates[6], dz=1.0)), True),
        ("move the camera", move(camera, dx=1.0), True),
        ("move the light", move(light, dz=-1.0), True),
        ("move the floor (used once: a mover from now on)", move(bpy.data.objects["Floor"], dz=-0.5), False),
        ("move the floor again", move(bpy.data.objects["Floor"], dz=0.25), True),
        ("move a box inside the instanced collection", move(box, dz=0.5), False),
        ("move the instancer", move(instancer, dx=-1.0), False),
        ("hide a duplicate", lambda: duplicates[8].hide_set(True), False),
        ("show it", lambda: duplicates[8].hide_set(False), False),
        ("scale a duplicate to nothing (no instance)", scale(duplicates[9], 0.0), False),
        ("scale it back", scale(duplicates[9], 1.0), False),
        ("move a duplicate out of range", move(duplicates[10], dx=1e13), "Dup10"),
        ("move it back", move(duplicates[10], dx=-1e13), False),
        ("move a duplicate again", move(duplicates[11], dz=0.3), True),
        # an analytic sphere stays in mesh 0: its row of the scene's spheres placed again
        ("move a sphere", move(bpy.data.objects["Marble"], dx=0.5), True),
        ("scale the other", scale(bpy.data.objects["Ball"], 1.5), True),
        ("move both", both(move(bpy.data.objects["Ball"], dz=0.2), move(bpy.data.objects["Marble"], dz=-0.2)), True),
        ("scale a sphere to nothing (its row gone)", scale(bpy.data.objects["Ball"], 0.0), False),
        ("move the other", move(bpy.data.objects["Marble"], dx=-0.5), True),
        ("scale it back", scale(bpy.data.objects["Ball"], 1.0), False),
        # Instancing and Parent name only a transform (Blender's rna_object), yet make new instances
        (
            "a duplicate instances its child at its vertices",
            lambda: setattr(duplicates[1], "instance_type", "VERTS"),
            False,
        ),
        (
            "the floor made a child of that instancer",
            lambda: setattr(bpy.data.objects["Floor"], "parent", duplicates[1]),
            False,
        ),
        ("the floor's parent cleared", lambda: setattr(bpy.data.objects["Floor"], "parent", None), False),
        ("no instancing", lambda: setattr(duplicates[1], "instance_type", "NONE"), False),
        (
            "move the child of a duplicate (used once: a mover from now on)",
            move(bpy.data.objects["Kid"], dz=0.2),
            False,
        ),
        ("move it again", move(bpy.data.objects["Kid"], dz=0.2), True),
        # playback: a frame change names each animated object (transform and shading) and its action
        (
            "animate a duplicate's location",
            keyframes(duplicates[2], "location", [(1, (-3, 0, 0)), (9, (-3, 2, 1))]),
            False,
        ),
        ("frame 3", frame(3), True),
        ("frame 4", frame(4), True),
        ("animate the camera", keyframes(camera, "location", [(1, (0, -16, 7)), (9, (2, -15, 8))]), False),
        ("frame 6", frame(6), True),
        (
            "animate a sphere",
            keyframes(bpy.data.objects["Ball"], "location", [(1, (-2, -3, 0.5)), (9, (-2, -4, 2))]),
            False,
        ),
        ("frame 5 (the sphere moved)", frame(5), True),
        (
            "animate a duplicate's location and camera visibility",
            both(
                keyframes(duplicates[4], "location", [(1, (-1.4, 0, 0)), (9, (-1.4, -2, 0))]),
                keyframes(duplicates[4], "visible_camera", [(1, True), (7, False)]),
            ),
            False,
        ),
        ("frame 7 (a visibility keyframed: walked)", frame(7), False),
        ("frame 2", frame(2), False),
        ("that animation removed", lambda: duplicates[4].animation_data_clear(), False),
        ("frame 5", frame(5), True),
        # reshaped objects: an object's own mesh read again, every other item kept
        ("edit a vertex of a box used once (read again: a mover from now on)", edit(blob), False),
        ("edit it again", edit(blob), True),
        (
            "edit it again, and hide it from camera rays",
            both(edit(blob), lambda: setattr(blob, "visible_camera", False)),
            False,
        ),
        ("show it to camera rays", lambda: setattr(blob, "visible_camera", True), False),
        ("edit it again (its slots as before)", edit(blob, -0.05), True),
        ("a vertex of it made not a number", edit(blob, math.nan), "Blob"),
        ("that vertex back (after a refusal: walked)", edit(blob, 0.0, at=(0.4, 0.4, 0.4)), False),
        ("subdivide it (a modifier added)", subdivide(1), False),
        ("subdivide it further (more triangles: not refittable)", subdivide(2), True),
        ("no subdivision", subdivide(0), True),
        # entering names the scene, then (a second evaluation) the object and its mesh
        ("into Edit Mode", edit_mode(True), None),
        ("move a vertex in Edit Mode", edit_in_edit_mode, True),
        ("move it again", edit_in_edit_mode, True),
        ("back to Object Mode", edit_mode(False), True),
        ("edit the mesh the duplicates share", edit(duplicates[0]), False),
        ("edit it again (its users' geometry changes: walked)", edit(duplicates[0]), False),
        ("move a duplicate after that", move(duplicates[11], dz=-0.3), True),
        ("delete the box's faces (no triangles: walked)", faces(False), False),
        ("give it faces again", faces(True), False),
        ("edit it after that", edit(blob), True),
        # keyframing the bone poses it: the skin is read again, a mover from then on
        ("animate the armature's bone", bone_keyframes, False),
        ("frame 8 (the skin deformed)", frame(8), True),
        ("frame 9 (the skin deformed again)", frame(9), True),
        ("animate a shape key", shape_keyframes, False),
        # keyframing the shape key changes the mesh under 4.2 (a mover from then on), not under 5.0
        ("frame 3 (both deformed)", frame(3), None),
        ("frame 5", frame(5), True),
        ("frame 1", frame(1), True),
        # a keyframed visibility is named as geometry on a frame change: walked
        ("keyframe the shape-keyed box's visibility", hide_keyframes, False),
        ("frame 3", frame(3), False),
        ("frame 4", frame(4), False),
        ("frame 5 (the box hidden)", frame(5), False),
        ("frame 2 (shown)", frame(2), False),
        # geometry nodes make instances where an edit names only the geometry: walked
        ("edit a box with a geometry-nodes modifier (a mover from now on)", edit(bpy.data.objects["Sprout"]), False),
        ("edit it again", edit(bpy.data.objects["Sprout"]), False),
        ("its modifier on (instances of a box at its corners)", sprout(True), False),
        ("its modifier off", sprout(False), False),
        # an update that changes no mesh makes no mover of the object
        ("a box keyframed once (animated, never moved)", still, False),
        ("its mesh updated, unchanged", lambda: bpy.data.objects["Still"].data.update(), True),
        ("its animation removed (in mesh 0 again)", lambda: bpy.data.objects["Still"].animation_data_clear(), False),
        # a constraint removed names only a transform: the object, not moved, goes back to mesh 0
        (
            "the constraint of a box it keeps in place removed",
            lambda: bpy.data.objects["Held"].constraints.remove(bpy.data.objects["Held"].constraints[0]),
            False,
        ),
        ("move that box (a mover from now on)", move(bpy.data.objects["Held"], dz=0.2), False),
        ("move it again", move(bpy.data.objects["Held"], dz=0.2), True),
    ]
    bpy.context.view_layer.update()
    placed.sync(bpy.context.evaluated_depsgraph_get(), scene)
    walked.sync(bpy.context.evaluated_depsgraph_get(), scene)
    handlers = (bpy.app.handlers.depsgraph_update_post, bpy.app.handlers.frame_change_post)
    for handler in handlers:
        handler.append(synced)
    try:
        for what, edit, skips in steps:
            reports.clear()
            edit()
            bpy.context.view_layer.update()
            assert not problems, f"{what}: {problems}"
            assert reports, f"{what}: no depsgraph update"
            mine, theirs = reports[-1]
            if isinstance(skips, str):  # both refuse it, naming the object
                assert isinstance(mine, ExportError) and isinstance(theirs, ExportError), (mine, theirs)
                assert skips in str(mine) and str(mine) == str(theirs), (mine, theirs)
                continue
            placed_any = any(r.placed_only for r, _ in reports)
            assert skips is None or placed_any == skips, (
                f"{what}: placed {[r.placed_only for r, _ in reports]}, expected {skips}"
            )
            assert not any(r.placed_only for _, r in reports)
        # an evaluation not synced (the sidebar's follow skips a hidden object): said, the next
        # sync walks, though its updates name only a move
        for handler in handlers:
            handler.remove(synced)
        duplicates[7].hide_set(True)
        bpy.context.view_layer.update()
        placed.missed(), walked.missed()
        for handler in handlers:
            handler.append(synced)
        reports.clear()
        move(duplicates[6], dx=0.2)()
        bpy.context.view_layer.update()
        assert not problems and reports and not reports[-1][0].placed_only, (problems, reports)
    finally:
        for handler in handlers:
            handler.remove(synced)
