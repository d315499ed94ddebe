"""Blender settings the render engine follows as Blender's own engines do (a probe, 2026-12-05):
a world animated over the frames of an animation, a frame with nothing to render inside an
animation, a particle emitter whose own geometry is not rendered, the view layer's Material
Override, and depth of field focused on an armature's bone. Each against what Blender's own
data says, or against Workbench's coverage of the same frame."""

from __future__ import annotations

import math

import bpy
import harness
import numpy as np
from checks_engine import ENGINE, use_engine
from checks_engine_frames import _exr_output, _exr_rgba

from bvhlab.blender import export_scene


def _background(scene, color):
    """The world's Background node (made where the world has no node tree yet) set to `color` at
    strength 1; returns its Color input."""
    world = scene.world
    if getattr(world, "use_nodes", True) is False:
        world.use_nodes = True  # Blender before 5.0 makes the default Background node here
    node = next(n for n in world.node_tree.nodes if n.bl_idname == "ShaderNodeBackground")
    node.inputs["Color"].default_value = (*color, 1.0)
    node.inputs["Strength"].default_value = 1.0
    return node.inputs["Color"]


def check_animated_world_colour_follows_the_frames(tmp_dir) -> None:
    """The world's Background colour keyed from (0.2, 0.3, 0.5) on frame 1 to (0.6, 0.1, 0.1) on
    frame 3, rendered as an animation with Persistent Data off and on: each frame's sky is the
    colour keyed there (every frame was the original's value: whatever was last written to it)."""
    scene = harness.empty_scene((32, 24))
    harness.add_camera((0, -10, 3), (0, 0, 0))
    harness.add_point_light((0, -3, 5))
    harness.add_box("Box", (0, 0, 0))
    color = _background(scene, (0.2, 0.3, 0.5))
    color.keyframe_insert("default_value", frame=1)
    color.default_value = (0.6, 0.1, 0.1, 1.0)
    color.keyframe_insert("default_value", frame=3)  # two keys: frame 2 halfway (Bézier, symmetric)
    scene.frame_start, scene.frame_end = 1, 3
    scene.frame_set(3)  # the original's value is frame 3's: frames 1 and 2 must not show it
    use_engine(scene, backend="cpu", render_supersampling=1)
    expected = [(0.2, 0.3, 0.5), (0.4, 0.2, 0.3), (0.6, 0.1, 0.1)]
    for persistent in (False, True):
        scene.render.use_persistent_data = persistent
        _exr_output(scene, tmp_dir / f"world{int(persistent)}_")
        assert bpy.ops.render.render(animation=True) == {"FINISHED"}
        images = [_exr_rgba(p) for p in sorted(tmp_dir.glob(f"world{int(persistent)}_*.exr"))]
        assert len(images) == 3, len(images)
        for frame, (image, want) in enumerate(zip(images, expected), start=1):
            sky = image[0, 0, :3]  # a corner: the sky
            assert np.allclose(sky, want, atol=2e-3), (persistent, frame, sky.tolist(), want)


def check_a_frame_with_nothing_to_render_is_the_world(tmp_dir) -> None:
    """The only mesh hidden for render on frame 2 of 1-3: the animation writes all three frames,
    frame 2 the world's colour alone (it stopped at frame 2 with "no mesh in scope", frame 3
    lost); a still F12 of nothing renders the world too, with a warning."""
    scene = harness.empty_scene((32, 24))
    harness.add_camera((0, -6, 0), (0, 0, 0))
    harness.add_point_light((0, -3, 5))
    box = harness.add_box("Box", (0, 0, 0), size=3.0)
    _background(scene, (0.1, 0.2, 0.3))
    for frame, hidden in ((1, False), (2, True), (3, False)):
        box.hide_render = hidden
        box.keyframe_insert("hide_render", frame=frame)
    scene.frame_start, scene.frame_end = 1, 3
    use_engine(scene, backend="cpu", render_supersampling=1)
    for persistent in (False, True):
        scene.render.use_persistent_data = persistent
        _exr_output(scene, tmp_dir / f"gap{int(persistent)}_")
        assert bpy.ops.render.render(animation=True) == {"FINISHED"}
        files = sorted(tmp_dir.glob(f"gap{int(persistent)}_*.exr"))
        assert len(files) == 3, [f.name for f in files]
        centre = [_exr_rgba(f)[12, 16, :3] for f in files]
        assert not np.allclose(centre[0], (0.1, 0.2, 0.3), atol=1e-3), centre[0]  # the box
        assert np.allclose(centre[1], (0.1, 0.2, 0.3), atol=1e-3), centre[1]  # the world alone
        assert np.allclose(centre[2], centre[0], atol=1e-6), (centre[2], centre[0])
    scene.frame_set(2)
    assert bpy.ops.render.render() == {"FINISHED"}


def _coverage(tmp_dir, name: str, engine: str) -> np.ndarray:
    """The frame's alpha > 0.5 with Film ▸ Transparent, rendered by `engine`."""
    scene = bpy.context.scene
    scene.render.engine = engine
    scene.render.film_transparent = True
    if engine == "BLENDER_WORKBENCH":
        scene.display.render_aa = "OFF"
    _exr_output(scene, tmp_dir / name)
    scene.render.filepath = str(tmp_dir / f"{name}.exr")
    assert bpy.ops.render.render(write_still=True) == {"FINISHED"}
    return _exr_rgba(tmp_dir / f"{name}.exr")[..., 3] > 0.5


def check_a_hidden_particle_emitter_is_not_rendered(tmp_dir) -> None:
    """A plate emitting 30 object particles with Show Emitter off for render: the particles are
    rendered, the plate not (it was: 231 pixels covered against Workbench's 137); Show Emitter on,
    both. Coverage against Workbench's, within a pixel or two at the edges."""
    scene = harness.empty_scene((64, 48))
    harness.add_camera((0, -9, 7), (0, 0, 0))
    harness.add_point_light((0, -3, 6))
    bpy.ops.mesh.primitive_plane_add(size=3.0)
    plate = bpy.context.active_object
    particle = harness.add_box("Grain", (0, 0, -50), size=0.25)
    plate.modifiers.new("Particles", "PARTICLE_SYSTEM")
    settings = plate.particle_systems[0].settings
    settings.count, settings.frame_start, settings.frame_end, settings.lifetime = 30, 1, 1, 1000
    settings.physics_type, settings.normal_factor = "NO", 0.0
    settings.render_type, settings.instance_object, settings.particle_size = "OBJECT", particle, 1.0
    settings.use_rotation_instance = False
    scene.frame_set(2)
    for shown in (False, True):
        plate.show_instancer_for_render = shown
        use_engine(scene, backend="cpu", render_supersampling=1)
        ours = _coverage(tmp_dir, f"emitter{int(shown)}_bvhlab", ENGINE)
        theirs = _coverage(tmp_dir, f"emitter{int(shown)}_workbench", "BLENDER_WORKBENCH")
        apart = int((ours != theirs).sum())
        assert theirs.sum() > 40 and apart <= max(4, theirs.sum() // 50), (shown, int(ours.sum()), int(theirs.sum()))
        if not shown:
            plate_only = theirs.sum()
        else:
            assert theirs.sum() > plate_only + 40, "the plate shows when its emitter is shown"


def check_material_override_stands_in_every_slot(tmp_dir) -> None:
    """A blue box, then the view layer's Material Override set to a red material: the box renders
    red, as in Cycles (it stayed blue, no warning); cleared, blue again (Persistent Data on: the
    slots are read again when the override changes)."""
    scene = harness.empty_scene((32, 24))
    harness.add_camera((0, -6, 2), (0, 0, 0))
    harness.add_point_light((0, -4, 4))
    box = harness.add_box("Box", (0, 0, 0), size=2.5)
    box.data.materials.append(_plain("Blue", (0.0, 0.1, 0.9)))
    use_engine(scene, backend="cpu", render_supersampling=1)
    scene.render.use_persistent_data = True
    view_layer = bpy.context.view_layer
    red = _plain("Red", (0.9, 0.05, 0.0))
    for override, wanted in ((None, 2), (red, 0), (None, 2)):
        view_layer.material_override = override
        _exr_output(scene, tmp_dir / f"override_{wanted}")
        scene.render.filepath = str(tmp_dir / f"override_{wanted}.exr")
        assert bpy.ops.render.render(write_still=True) == {"FINISHED"}
        centre = _exr_rgba(tmp_dir / f"override_{wanted}.exr")[12, 16, :3]
        assert int(np.argmax(centre)) == wanted and centre[wanted] > 3 * np.delete(centre, wanted).max(), (
            override,
            centre.tolist(),
        )


def _plain(name: str, color) -> bpy.types.Material:
    material = bpy.data.materials.new(name)
    material.use_nodes = True
    material.node_tree.nodes["Principled BSDF"].inputs["Base Color"].default_value = (*color, 1.0)
    material.diffuse_color = (*color, 1.0)
    return material


def check_depth_of_field_focuses_on_a_bone() -> None:
    """Focus on Object an armature and a bone of it: the exported focus distance is the bone head's
    along the view axis (it was the armature's origin's: 8 against 18)."""
    scene = harness.empty_scene((32, 24))
    camera = harness.add_camera((0, -10, 0), (0, 0, 0))
    harness.add_point_light((0, -3, 5))
    harness.add_box("Box", (0, 0, 0))
    armature = bpy.data.objects.new("Rig", bpy.data.armatures.new("Rig"))
    scene.collection.objects.link(armature)
    armature.location = (0, -2, 0)
    bpy.context.view_layer.objects.active = armature
    bpy.ops.object.mode_set(mode="EDIT")
    bone = armature.data.edit_bones.new("Far")
    bone.head, bone.tail = (0, 10, 0), (0, 10, 1)
    bpy.ops.object.mode_set(mode="OBJECT")
    dof = camera.data.dof
    dof.use_dof, dof.aperture_fstop, dof.focus_object = True, 0.5, armature
    bpy.context.view_layer.update()
    assert math.isclose(export_scene(bpy.context).camera.focus_distance, 8.0, rel_tol=1e-5)  # the origin
    if not hasattr(dof, "focus_subtarget"):
        return  # Blender without bone focus
    dof.focus_subtarget = "Far"
    bpy.context.view_layer.update()
    got = export_scene(bpy.context).camera.focus_distance
    assert math.isclose(got, 18.0, rel_tol=1e-5), got


def check_a_mirrored_camera_mirrors_the_exported_view() -> None:
    """A camera scaled by -1 on x exports a mirrored lens, scaled by -1 twice not (the F12 and
    viewport images against Cycles: cameras/mirrored)."""
    harness.empty_scene((32, 24))
    camera = harness.add_camera((0, -10, 0), (0, 0, 0))
    harness.add_box("Box", (0, 0, 0))
    for scale, mirrored in (((1, 1, 1), False), ((-1, 1, 1), True), ((-1, -1, 1), False), ((1, 1, -2), True)):
        camera.scale = scale
        bpy.context.view_layer.update()
        assert export_scene(bpy.context).camera.mirrored is mirrored, scale


def check_principled_metal_lies_over_transmission() -> None:
    """A Principled BSDF's metal lies over its dielectric base, whose transmission is the rest's:
    metallic 1 with transmission 1 exports a mirror (it exported reflective 1 and transparent 1,
    twice the light arriving), metallic 0.25 with transmission 1 reflects 0.25 and transmits 0.75."""
    harness.empty_scene((16, 12))
    harness.add_camera((0, -10, 0), (0, 0, 0))
    box = harness.add_box("Box", (0, 0, 0))
    material = _plain("Metal glass", (0.8, 0.8, 0.8))
    box.data.materials.append(material)
    principled = material.node_tree.nodes["Principled BSDF"]
    for metallic, want in ((1.0, (1.0, 0.0)), (0.25, (0.25, 0.75)), (0.0, (0.0, 1.0))):
        principled.inputs["Metallic"].default_value = metallic
        principled.inputs["Transmission Weight"].default_value = 1.0
        exported = export_scene(bpy.context).materials[0]
        got = (exported.reflective, exported.transparent)
        assert np.allclose(got, want, atol=1e-6), (metallic, got)


def check_curves_text_surfaces_and_metaballs_are_exported_once() -> None:
    """A text, a bevelled curve, a filled 2D curve, a NURBS surface and a metaball: the depsgraph
    shows each as itself and as an instance of type MESH holding its surface, which Cycles renders
    once; the export has exactly the triangles of that surface in the world (every one was
    exported twice: through the object's to_mesh too), and a curve without a surface has none."""
    adders = {
        "text": lambda: bpy.ops.object.text_add(),
        "bevelled curve": lambda: (bpy.ops.curve.primitive_bezier_circle_add(), _set_data(bevel_depth=0.2)),
        "filled 2D curve": lambda: (
            bpy.ops.curve.primitive_bezier_circle_add(),
            _set_data(dimensions="2D", fill_mode="BOTH"),
        ),
        "surface": lambda: bpy.ops.surface.primitive_nurbs_surface_sphere_add(),
        "metaball": lambda: bpy.ops.object.metaball_add(),
    }
    for kind, add in adders.items():
        harness.empty_scene((32, 24))
        harness.add_camera((0, -9, 7), (0, 0, 0))
        add()
        obj = bpy.context.active_object
        obj.location, obj.rotation_euler = (0.3, 0.2, 0.5), (0.4, 0.1, 0.7)
        bpy.context.view_layer.update()
        depsgraph = bpy.context.evaluated_depsgraph_get()
        evaluated = obj.evaluated_get(depsgraph)
        mesh = evaluated.to_mesh()
        mesh.calc_loop_triangles()
        corners = np.array([list(t.vertices) for t in mesh.loop_triangles], np.int64).reshape(-1, 3)
        local = np.array([v.co[:] for v in mesh.vertices], np.float64)
        evaluated.to_mesh_clear()
        world = np.array(obj.matrix_world)
        expected = (local @ world[:3, :3].T + world[:3, 3])[corners]
        exported = export_scene(bpy.context).flattened().triangles.astype(np.float64)
        assert len(expected) > 40 and len(exported) == len(expected), (kind, len(exported), len(expected))
        # the same corners and area (a quad may be split along the other diagonal)
        a, b = exported.reshape(-1, 3), expected.reshape(-1, 3)
        apart = np.linalg.norm(a[:, None] - b[None], axis=-1)
        assert apart.min(1).max() < 1e-4 and apart.min(0).max() < 1e-4, kind
        assert abs(_area(exported) - _area(expected)) <= 1e-4 * _area(expected), kind
    harness.empty_scene((32, 24))
    harness.add_camera((0, -9, 7), (0, 0, 0))
    bpy.ops.curve.primitive_bezier_circle_add()  # a curve with no surface: nothing to export
    harness.add_box("Box", (0, 0, 0))
    assert len(export_scene(bpy.context).flattened().triangles) == 12


def _area(triangles: np.ndarray) -> float:
    return float(
        0.5
        * np.linalg.norm(np.cross(triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0]), axis=1).sum()
    )


def _set_data(**values) -> None:
    for name, value in values.items():
        setattr(bpy.context.active_object.data, name, value)
