"""A LiveScene synced from every depsgraph update, as the Rendered viewport syncs it, against one
that walks the depsgraph at every sync (`place_from_updates=False`): where the updates say only
instances, the camera or the light moved, the sync takes their matrices from the updates alone
(bvhlab/blender/placed_only.py) and must export exactly what the walk exports; anything else must
walk. Under every Blender: what `depsgraph.updates` names for each edit is Blender's, and the
skipped walk is only right where each version names what this expects."""

from __future__ import annotations

import warnings

import bpy
import harness
import numpy as np

from bvhlab.blender import ExportError, LiveScene

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
    bpy.context.view_layer.update()
    return scene, camera, light, duplicates, parent, box, instancer


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

    # (what, the edit, whether the sync may skip the walk)
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
        ("move a duplicate out of range", move(duplicates[10], dx=1e13), False),
        ("move it back", move(duplicates[10], dx=-1e13), False),
        ("move a duplicate again", move(duplicates[11], dz=0.3), True),
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
            if what == "move a duplicate out of range":  # both refuse it, naming it
                assert isinstance(mine, ExportError) and isinstance(theirs, ExportError), (mine, theirs)
                assert "Dup10" in str(mine) and str(mine) == str(theirs), (mine, theirs)
                continue
            placed_any = any(r.placed_only for r, _ in reports)
            assert placed_any == skips, f"{what}: placed {[r.placed_only for r, _ in reports]}, expected {skips}"
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
