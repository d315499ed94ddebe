"""Export checks on small scenes made on the spot: scope, instances, material slots, spheres,
camera sensor fits, files, and bad input (clear errors, warnings for substitutes)."""

from __future__ import annotations

import math
import warnings

import bpy
import harness
import numpy as np

import bvhlab
from bvhlab.blender import SPHERE_PROPERTY, ExportError, SubstituteWarning, export_scene, export_scene_file
from bvhlab.blender.compat import ensure_shader_tree


def _expect_error(fragment: str, **kwargs) -> str:
    try:
        export_scene(bpy.context, **kwargs)
    except ExportError as error:
        assert fragment in str(error), f"'{fragment}' not in '{error}'"
        return str(error)
    raise AssertionError(f"no ExportError ('{fragment}')")


def _world_cube_corners(obj) -> np.ndarray:
    """The 8 corners of a harness cube through mathutils (independent of bvhlab's numpy)."""
    return np.array([tuple(obj.matrix_world @ v.co) for v in obj.data.vertices])


def check_scope_selected_and_visible() -> None:
    harness.boxes_scene()
    objects = bpy.context.scene.objects
    for obj in objects:
        obj.select_set(obj.name == "Box B")
    selected = export_scene(bpy.context, scope="selected")
    assert len(selected.triangles) == 12
    corners = _world_cube_corners(objects["Box B"])
    np.testing.assert_allclose(
        np.sort(np.unique(selected.triangles.reshape(-1, 3), axis=0), 0), np.sort(corners, 0), atol=1e-5
    )
    assert len(export_scene(bpy.context, scope="visible").triangles) == 36
    objects["Box C"].hide_set(True)
    assert len(export_scene(bpy.context, scope="visible").triangles) == 24


def check_collection_instances() -> None:
    """A collection instanced twice by empties exports twice, at each instance's transform: as two
    instances of Box A's mesh, which the prototype shares with Box A (a third instance)."""
    harness.boxes_scene()
    source = bpy.data.collections.new("Source")
    mesh = bpy.data.objects["Box A"].data
    prototype = bpy.data.objects.new("Prototype", mesh)
    source.objects.link(prototype)
    prototype.location = (0.5, 0.0, 0.0)
    for i, location in enumerate([(10.0, 0.0, 0.0), (0.0, 10.0, 2.0)]):
        empty = bpy.data.objects.new(f"Instance {i}", None)
        empty.instance_type, empty.instance_collection = "COLLECTION", source
        empty.location = location
        bpy.context.scene.collection.objects.link(empty)
    instanced = export_scene(bpy.context)
    assert len(instanced.triangles) == 24 and len(instanced.meshes) == 1 and len(instanced.meshes[0]) == 12
    assert len(instanced.instance_mesh) == 1 + 3  # mesh 0 (Boxes B and C) once, Box A's mesh three times
    exported = instanced.flattened()
    assert len(exported.triangles) == 36 + 24
    points = exported.triangles.reshape(-1, 3)
    for location in [(10.0, 0.0, 0.0), (0.0, 10.0, 2.0)]:
        corner = np.add(location, (0.5 + 0.5, 0.5, 0.5))  # instance offset + prototype offset + corner
        assert np.abs(points - corner).max(1).min() < 1e-5, f"instance at {location} missing"


def check_material_slots_per_triangle() -> None:
    """Faces with material_index 0/1 export to the two materials, triangle by triangle."""
    harness.boxes_scene()
    box = bpy.data.objects["Box A"]
    for name, color, metallic in (("Red", (1.0, 0.0, 0.0), 0.0), ("Chrome", (0.9, 0.9, 0.9), 1.0)):
        material = bpy.data.materials.new(name)
        bsdf = ensure_shader_tree(material).nodes["Principled BSDF"]
        bsdf.inputs["Base Color"].default_value = (*color, 1.0)
        bsdf.inputs["Metallic"].default_value = metallic
        box.data.materials.append(material)
    face_slots = [0, 1, 1, 0, 1, 0]
    box.data.polygons.foreach_set("material_index", face_slots)
    box.data.update()
    for obj in bpy.context.scene.objects:
        obj.select_set(obj is box)
    exported = export_scene(bpy.context, scope="selected")
    rows = exported.material_table()[exported.tri_material]
    assert np.array_equal(rows[:, 3], np.repeat(face_slots, 2).astype(np.float32))  # reflective = slot 1
    assert np.allclose(rows[np.repeat(face_slots, 2) == 0, :3], (1.0, 0.0, 0.0))


def check_analytic_sphere_radius() -> None:
    """Centre = world location; radius = largest scaled half extent of the bounds."""
    harness.boxes_scene()
    bpy.ops.mesh.primitive_uv_sphere_add(radius=0.5, location=(3.0, 1.0, 2.0))
    ball = bpy.context.object
    ball.scale = (2.0, 3.0, 1.0)
    ball[SPHERE_PROPERTY] = True
    exported = export_scene(bpy.context)
    assert len(exported.spheres) == 1 and len(exported.triangles) == 36
    np.testing.assert_allclose(exported.spheres[0], (3.0, 1.0, 2.0, 1.5), atol=1e-5)
    # scaled to nothing (a common way to hide an instance; an animated sphere shrinking away): no
    # sphere, as Blender renders nothing there; the export failed ("has no extent")
    ball.scale = (0.0, 0.0, 0.0)
    exported = export_scene(bpy.context)
    assert len(exported.spheres) == 0 and len(exported.triangles) == 36
    ball.scale = (2.0, 3.0, 1.0)
    assert len(export_scene(bpy.context).spheres) == 1


def check_camera_sensor_fits() -> None:
    """Vertical field of view for every sensor fit, landscape and portrait, against view_frame."""
    scene = harness.boxes_scene()
    camera = scene.camera
    camera.data.sensor_height = 20.0
    for fit in ("AUTO", "HORIZONTAL", "VERTICAL"):
        for resolution in ((64, 48), (48, 64), (100, 100)):
            camera.data.sensor_fit = fit
            scene.render.resolution_x, scene.render.resolution_y = resolution
            frame = np.array([tuple(v) for v in camera.data.view_frame(scene=scene)])
            expected = math.degrees(2 * math.atan(np.abs(frame[:, 1]).max() / abs(frame[0, 2])))
            got = export_scene(bpy.context).camera.fov_y
            assert abs(got - expected) < 1e-4, (fit, resolution, got, expected)


def check_scene_file_round_trip(tmp_dir) -> None:
    harness.boxes_scene()
    path = tmp_dir / "boxes.npz"
    exported = export_scene_file(path, bpy.context)
    loaded = bvhlab.Scene.load(path)
    assert np.array_equal(loaded.triangles, exported.triangles)
    assert loaded.camera == exported.camera and loaded.light == exported.light
    assert loaded.materials == exported.materials


def check_bad_input_errors() -> None:
    harness.boxes_scene()
    for obj in bpy.context.scene.objects:
        obj.select_set(False)
    _expect_error("no mesh in scope", scope="selected")
    _expect_error("unknown scope", scope="everything")
    box = bpy.data.objects["Box B"]
    box.data.vertices[3].co.x = float("nan")
    message = _expect_error("not a finite number")
    assert "Box B" in message
    box.data.vertices[3].co.x = 0.6
    bpy.context.scene.camera = None
    _expect_error("no camera")


def check_a_sheared_camera_is_warned_of() -> None:
    """A camera under an unevenly scaled parent, turned against its axes, has slanted axes, which
    Blender and Cycles render through and bvhlab does not (square axes along its view and up): an
    ExportWarning says so (the audit: the frame was ~9 px off on 120 × 90, silently). A parent
    scaled evenly, or unevenly along the camera's own axes, shears nothing: no warning."""
    scene = harness.boxes_scene()
    rig = bpy.data.objects.new("Rig", None)
    scene.collection.objects.link(rig)
    scene.camera.parent = rig
    scene.camera.rotation_euler = (math.radians(80), 0.0, math.radians(25))

    def sheared(scale, rotation) -> bool:
        rig.scale, scene.camera.rotation_euler = scale, rotation
        bpy.context.view_layer.update()
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            export_scene(bpy.context)
        return any("is sheared" in str(w.message) for w in caught)

    turned = (math.radians(80), 0.0, math.radians(25))
    assert sheared((1.0, 2.5, 1.0), turned)
    assert not sheared((2.0, 2.0, 2.0), turned)
    assert not sheared((1.0, 2.5, 1.0), (0.0, 0.0, 0.0))  # scaled along the camera's own axes


def check_a_bad_light_material_or_world_is_named() -> None:
    """A light, material or world whose values a scene refuses (not a number here) is named in the
    ExportError, as a mesh's bad vertex names its object (the audit: "light position must be
    finite", without saying which light)."""
    harness.boxes_scene()
    light = next(o for o in bpy.context.scene.objects if o.type == "LIGHT")
    light.location.y = math.nan
    assert f"light '{light.name}'" in _expect_error("must be finite")
    light.location.y = -3.0
    world = bpy.context.scene.world
    world.color = (math.nan, 0.0, 0.0)  # what 4.x reads without nodes; 5.x's world has a Background node
    background = world.node_tree.nodes.get("Background") if world.node_tree is not None else None
    if background is not None:
        background.inputs["Color"].default_value = (math.nan, 0.0, 0.0, 1.0)
    assert "world 'World'" in _expect_error("must be finite")
    world.color = (0.2, 0.3, 0.5)
    if background is not None:
        background.inputs["Color"].default_value = (0.2, 0.3, 0.5, 1.0)
    material = bpy.data.materials.new("Not a number")
    ensure_shader_tree(material)
    material.node_tree.nodes["Principled BSDF"].inputs["Base Color"].default_value = (math.nan, 0.5, 0.5, 1.0)
    bpy.data.objects["Box A"].data.materials.append(material)
    assert "material 'Not a number'" in _expect_error("must be finite")


def check_loose_vertices_far_or_not_a_number_are_not_refused() -> None:
    """A vertex in no face (a loose one) that is not a number, or far outside the coordinate range,
    is not rendered (Cycles renders the mesh without it): the export is the mesh's triangles as
    without it (the audit: F12, Build and Render refused the scene). A NaN vertex a face uses is
    still refused (check_bad_input_errors)."""
    harness.boxes_scene()
    expected = export_scene(bpy.context).triangles
    mesh = bpy.data.objects["Box A"].data
    mesh.vertices.add(1)
    for co in ((math.nan, 0.0, 0.0), (1e13, 0.0, 0.0), (0.0, -math.inf, 0.0)):
        mesh.vertices[-1].co = co
        mesh.update()
        bpy.context.view_layer.update()
        got = export_scene(bpy.context).triangles
        assert np.array_equal(got, expected), co


def check_missing_camera_and_light_substituted() -> None:
    """Without a camera (when not required) or a light, bvhlab's defaults stand in, with warnings."""
    harness.boxes_scene()
    bpy.context.scene.camera = None
    bpy.data.objects.remove(bpy.data.objects["Light"])
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        exported = export_scene(bpy.context, require_camera=False)
    messages = [str(w.message) for w in caught if issubclass(w.category, SubstituteWarning)]
    assert any("no camera" in m for m in messages) and any("no visible light" in m for m in messages), messages
    assert exported.camera is not None and exported.light is not None


def check_linked_duplicates_of_a_mesh_in_edit_mode() -> None:
    """Two objects sharing one mesh, either in Edit Mode: both are exported, each where it stands
    (the probe: under 4.2 the export failed, KeyError 'position'; under 4.5 one box was left out,
    its evaluated mesh the edit mesh's wrapper though its own mode was Object Mode). Against the
    corners of both through mathutils, with instancing and without."""
    scene = harness.empty_scene((32, 24))
    harness.add_camera((0, -12, 2), (1.5, 0, 0))
    a = harness.add_box("A", (0, 0, 0))
    b = bpy.data.objects.new("B", a.data)  # a linked duplicate
    scene.collection.objects.link(b)
    b.location, b.rotation_euler = (3, 0, 0), (0.3, 0, 0)
    bpy.context.view_layer.update()
    corners = np.concatenate([_world_cube_corners(a), _world_cube_corners(b)])
    for edited in (a, b):
        bpy.context.view_layer.objects.active = edited
        edited.select_set(True)
        bpy.ops.object.mode_set(mode="EDIT")
        try:
            for instancing in (True, False):
                got = export_scene(bpy.context, instancing=instancing).flattened().triangles.reshape(-1, 3)
                assert len(got) == 2 * 12 * 3, (edited.name, instancing, len(got))
                # every exported vertex is a corner of one of the boxes, and every corner is exported
                d = np.abs(got[:, None, :] - corners[None, :, :]).max(-1)
                assert d.min(1).max() < 1e-5 and d.min(0).max() < 1e-5, (edited.name, instancing)
        finally:
            bpy.ops.object.mode_set(mode="OBJECT")


def check_a_scene_or_view_layer_not_yet_evaluated() -> None:
    """export_scene of another scene, or of a view layer just made: Blender has not evaluated them
    (`view_layer.depsgraph` is None) and the export raised AttributeError (probe); now evaluated
    first. Each exports its own objects: the other scene's box only, the new layer's both boxes."""
    harness.empty_scene((32, 24))
    a = harness.add_box("A", (0, 0, 0))
    other = bpy.data.scenes.new("Other")
    other.collection.objects.link(bpy.data.objects.new("B", a.data))
    try:
        assert other.view_layers[0].depsgraph is None
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", SubstituteWarning)  # no camera, no light
            assert len(export_scene(other, require_camera=False).flattened().triangles) == 12
            scene = bpy.context.scene
            scene.collection.objects.link(bpy.data.objects.new("C", a.data))
            layer = scene.view_layers.new("Fresh")
            assert layer.depsgraph is None

            class Context:  # what export_scene reads of a context
                pass

            context = Context()
            context.scene, context.view_layer = scene, layer
            assert len(export_scene(context, require_camera=False).flattened().triangles) == 24
    finally:
        bpy.data.scenes.remove(other)
