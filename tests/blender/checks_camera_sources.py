"""The camera and frame F12 is handed rather than the scene's own (helper probe, 2026-12-07): a
Sequencer scene strip's camera (RenderEngine.camera_override; the strip's scene rendered through
its own camera before, or refused without one), a scene rendered by another scene's compositor at
that scene's size (RenderEngine.resolution_x, _y; framed with its own resolution's aspect before:
a portrait frame squeezed into a landscape one), and a multi-view render whose second view's
camera is a panorama with the box overlay on (the whole F12 failed; the scene camera's panorama
dropped the overlay, said). Each against the same scene rendered directly through the camera at
the frame's size, alpha for alpha, which Cycles frames the same (the probe's runs)."""

from __future__ import annotations

import math

import bpy
import exr
import harness
import numpy as np


def _shot(resolution, cameras: dict, scene_camera: str | None):
    """A scene "Shot" at `resolution`, transparent, rendered by bvhlab: a 6×6 plane facing -Y at the
    origin and a unit cube at x = 3, and cameras 10 units in front (name → x), `scene_camera` its
    active one (None: no camera)."""
    harness.empty_scene(resolution)
    shot = bpy.context.scene
    shot.name = "Shot"
    shot.render.film_transparent = True
    shot.render.engine = "BVHLAB_WHITTED"
    shot.bvhlab.render_supersampling = 1
    harness.add_box("Plane", (0.0, 0.0, 0.0), size=1.0, scale=(6.0, 0.01, 6.0))
    harness.add_box("Cube", (3.0, 0.0, 0.0))
    made = {}
    for name, x in cameras.items():
        obj = bpy.data.objects.new(name, bpy.data.cameras.new(name))
        shot.collection.objects.link(obj)
        obj.location, obj.rotation_euler = (x, -10.0, 0.0), (math.pi / 2, 0.0, 0.0)
        made[name] = obj
    shot.camera = made.get(scene_camera)
    return shot, made


def _alpha(scene, tmp_dir, name: str) -> np.ndarray:
    """F12 of `scene`, its alpha (top row first)."""
    assert bpy.ops.render.render(scene=scene.name) == {"FINISHED"}
    settings = scene.render.image_settings
    settings.file_format, settings.color_mode, settings.color_depth = "OPEN_EXR", "RGBA", "32"
    settings.exr_codec = "NONE"
    path = tmp_dir / f"{name}.exr"
    bpy.data.images["Render Result"].save_render(str(path), scene=scene)
    return exr.read_exr(path)["A"]


def _main(resolution):
    main = bpy.data.scenes.new("Main")
    main.render.resolution_x, main.render.resolution_y = resolution
    main.render.resolution_percentage = 100
    main.render.film_transparent = True
    main.frame_start = main.frame_end = 1
    return main


def check_a_strips_camera_override_is_rendered_through(tmp_dir) -> None:
    for scene_camera in ("Left", None):  # the strip's scene's own camera sees nothing, or it has none
        shot, cameras = _shot((64, 48), {"Left": -30.0, "Right": 3.0}, "Right")
        want = _alpha(shot, tmp_dir, "direct")
        assert 0.05 < (want > 0.5).mean() < 0.9, (want > 0.5).mean()
        shot.camera = cameras.get(scene_camera)
        main = _main((64, 48))
        editor = main.sequence_editor_create()
        strips = editor.strips if hasattr(editor, "strips") else editor.sequences  # 5.0 renamed them
        strip = strips.new_scene("shot", shot, 1, 1)
        strip.scene_camera = cameras["Right"]
        got = _alpha(main, tmp_dir, f"strip_{scene_camera}")
        assert np.array_equal(got, want), (scene_camera, (got > 0.5).mean(), (want > 0.5).mean())


def _composite_other_scene(main, shot) -> None:
    """Main's compositor shows Shot's Render Layers (Blender 5.0 made the compositor a node group)."""
    if hasattr(main, "compositing_node_group"):
        tree = bpy.data.node_groups.new("Composite", "CompositorNodeTree")
        tree.interface.new_socket("Image", in_out="OUTPUT", socket_type="NodeSocketColor")
        main.compositing_node_group = tree
        layers, out = tree.nodes.new("CompositorNodeRLayers"), tree.nodes.new("NodeGroupOutput")
        layers.scene = shot
        tree.links.new(layers.outputs["Image"], out.inputs[0])
        return
    main.use_nodes = True
    tree = main.node_tree
    for node in list(tree.nodes):
        tree.nodes.remove(node)
    layers, out = tree.nodes.new("CompositorNodeRLayers"), tree.nodes.new("CompositorNodeComposite")
    layers.scene = shot
    tree.links.new(layers.outputs["Image"], out.inputs["Image"])
    if "Alpha" in out.inputs:  # 4.2's Composite node; later ones take the image's alpha
        tree.links.new(layers.outputs["Alpha"], out.inputs["Alpha"])


def check_another_scenes_compositor_frames_at_its_size(tmp_dir) -> None:
    shot, _ = _shot((64, 48), {"Camera": 0.0}, "Camera")
    want = _alpha(shot, tmp_dir, "direct")  # the plane across the frame's width, and the cube
    shot.render.resolution_x, shot.render.resolution_y = 48, 64  # its own setting portrait
    main = _main((64, 48))
    main.render.engine = "BLENDER_WORKBENCH"
    _composite_other_scene(main, shot)
    got = _alpha(main, tmp_dir, "composited")
    assert got.shape == want.shape == (48, 64), (got.shape, want.shape)
    columns = np.flatnonzero((got > 0.5).any(0))
    assert np.array_equal(got > 0.5, want > 0.5), (columns.min(), columns.max())


def _two_views(fisheye: str):
    """A multi-view render of the boxes by bvhlab (Cam_L for the left view, the scene camera, and
    Cam_R for the right one), the camera of view `fisheye` a 180° fisheye; returns the scene."""
    scene = harness.boxes_scene()
    render = scene.render
    left = scene.camera
    left.name = "Cam_L"
    render.use_multiview, render.views_format = True, "MULTIVIEW"
    render.views["left"].camera_suffix, render.views["right"].camera_suffix = "_L", "_R"
    right = left.copy()
    right.data, right.name = left.data.copy(), "Cam_R"
    scene.collection.objects.link(right)
    data = (left if fisheye == "left" else right).data
    data.type = "PANO"
    settings = data if hasattr(data, "panorama_type") else data.cycles  # 4.0 moved them
    settings.panorama_type, settings.fisheye_fov = "FISHEYE_EQUIDISTANT", math.radians(180)
    scene.render.engine = "BVHLAB_WHITTED"
    scene.bvhlab.render_supersampling = 1
    return scene


def check_each_views_camera_decides_whether_it_draws_the_overlay(tmp_dir) -> None:
    """A multi-view render whose scene camera (the left view's) is a fisheye and whose right view's
    camera is a perspective one: the right view draws the boxes, the left one not (every view lost
    them where the scene camera could not draw them: the review)."""
    from checks_stereo import views_pass

    scene = _two_views(fisheye="left")
    scene.bvhlab.render_overlay = False
    plain = views_pass(tmp_dir, "plain", "Combined.R")
    scene.bvhlab.render_overlay = True
    boxes = views_pass(tmp_dir, "boxes", "Combined.R")
    assert np.array_equal(boxes["left"], plain["left"])  # the fisheye's view: no boxes
    assert (boxes["right"] != plain["right"]).sum() > 50, (boxes["right"] != plain["right"]).sum()


def check_a_panorama_views_camera_drops_the_overlay_and_renders() -> None:
    scene = _two_views(fisheye="right")
    scene.bvhlab.render_overlay = True
    assert bpy.ops.render.render() == {"FINISHED"}
    record = harness.addon().state.last_final[harness.addon().state.key(scene)]
    assert record["views"] == ["left", "right"] and not record["cancelled"], record["views"]
    assert "the box overlay is not drawn through fisheye cameras" in record["unrendered"], record["unrendered"]
