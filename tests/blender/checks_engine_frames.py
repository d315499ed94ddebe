"""The render engine over animation frames: bpy.ops.render.render(animation=True) with Persistent
Data, and a real Blender binary rendering frames from the command line; each frame's EXR against
the CPU reference tracer on that frame's export."""

from __future__ import annotations

import bpy
import exr
import harness
import numpy as np
from checks_engine import ENGINE, _last_final, compare_images, reference, use_engine

from bvhlab.blender import export_scene


def _exr_rgba(path) -> np.ndarray:
    channels = exr.read_exr(path)
    return np.stack([channels[c] for c in "RGBA"], -1)


def _red_centroid_x(image: np.ndarray) -> float:
    """Mean column of the red ball's pixels (red well above green and blue)."""
    red = (image[..., 0] > image[..., 1] + 0.15) & (image[..., 0] > image[..., 2] + 0.15)
    assert red.sum() > 30, "the red ball is not in the picture"
    return float(np.nonzero(red)[1].mean())


def _exr_output(scene, path_prefix) -> None:
    scene.render.filepath = str(path_prefix)
    settings = scene.render.image_settings
    settings.file_format, settings.exr_codec, settings.color_depth, settings.color_mode = (
        "OPEN_EXR",
        "NONE",
        "32",
        "RGBA",
    )


def check_animation_frames(tmp_dir) -> None:
    """bpy.ops.render.render(animation=True) over frames 1-3 of the animated bundled scene (what
    `blender -b moving_ball.blend -a` runs), Persistent Data on: three EXR files, each equal to
    bvhlab.render of that frame's export; the red ball moves right from frame to frame; between
    frames the two moving objects are placed again, none read again, and the tree is refit."""
    scene = harness.open_scene("moving_ball")
    use_engine(scene, backend="cpu", render_supersampling=1)
    scene.render.use_persistent_data = True
    _exr_output(scene, tmp_dir / "anim_")
    assert bpy.ops.render.render(animation=True) == {"FINISHED"}
    files = sorted(tmp_dir.glob("anim_*.exr"))
    assert [f.name for f in files] == ["anim_0001.exr", "anim_0002.exr", "anim_0003.exr"], files
    record = _last_final(scene)
    totals = record["totals"]
    assert (totals.full_syncs, totals.objects_read, totals.objects_moved) == (1, 3, 4), totals
    assert record["tree"] == "refit", record["tree"]
    centroids, first_light = [], None
    for frame, path in zip((1, 2, 3), files):
        scene.frame_set(frame)
        image = _exr_rgba(path)
        exported = _with_light_of(export_scene(bpy.context), first_light)  # an animation keeps frame 1's
        first_light = first_light or exported.light
        compare_images(image, reference(scene, samples_per_axis=1, exported=exported)[0], "cpu")
        centroids.append(_red_centroid_x(image))
    assert centroids[0] + 10 < centroids[1] < centroids[2] - 10, f"the ball does not move right: {centroids}"


def _with_light_of(exported, light):
    """`exported` lit by `light` (an earlier frame's), where given."""
    if light is not None:
        exported.light = light
    return exported


def check_keyframed_visibility_follows_the_frames(tmp_dir) -> None:
    """Object ▸ Visibility flags keyframed (Box A hidden from camera rays from frame 2; the crate's
    instancer 'Crate 1' a holdout from frame 2, on a transparent film): an animation render
    shows each frame's flags, every frame equal to the CPU reference of that frame's export. They
    were read from the original objects, which a render's depsgraph never updates: every frame
    showed frame 1's (the UI frame's) flags, Box A and the crate's alpha in all three."""
    from checks_cameras import camera_scene

    scene = camera_scene((64, 48))
    box, crate = bpy.data.objects["Box A"], bpy.data.objects["Crate 1"]
    for frame, on in ((1, False), (2, True)):
        box.visible_camera = not on
        box.keyframe_insert("visible_camera", frame=frame)
        crate.is_holdout = on
        crate.keyframe_insert("is_holdout", frame=frame)
    scene.frame_start, scene.frame_end = 1, 3
    scene.frame_set(1)
    scene.render.film_transparent = True
    use_engine(scene, backend="cpu", render_supersampling=1)
    _exr_output(scene, tmp_dir / "flags_")
    assert bpy.ops.render.render(animation=True) == {"FINISHED"}
    images = [_exr_rgba(p) for p in sorted(tmp_dir.glob("flags_*.exr"))]
    assert len(images) == 3, len(images)
    first_light = None
    for frame, image in zip((1, 2, 3), images):
        scene.frame_set(frame)  # the view layer's depsgraph writes the frame's flags to the originals
        exported = _with_light_of(export_scene(bpy.context), first_light)
        first_light = first_light or exported.light
        compare_images(image, reference(scene, samples_per_axis=1, exported=exported)[0], "cpu")
    holes = (images[1][..., 3] == 0) & (images[0][..., 3] > 0)  # the crate held out from frame 2
    changed = np.abs(images[1] - images[0]).max(-1) > 1e-3
    assert holes.sum() > 20 and changed.sum() > holes.sum() + 20, (holes.sum(), changed.sum())
    assert np.array_equal(images[1], images[2])
    scene.frame_set(1)


def check_animation_light_is_steady(tmp_dir) -> None:
    """A static light over a static floor while a ball rolls away, frames 1-3, Persistent Data
    off and on: the floor's pixels are the same on every frame (the light's intensity was measured
    again each frame from the distances to the geometry: 0.416 → 0.121 → 0.087 at a floor pixel),
    and a still F12 afterwards measures it again for the scene as it is then."""
    scene = harness.empty_scene((48, 36))
    harness.add_camera((0, -10, 6), (0, 0, 0), lens=30)
    harness.add_point_light((0, 0, 5))
    floor = harness.add_box("Floor", (0, 0, -0.05), scale=(12, 12, 0.1))
    ball = harness.add_box("Ball", (3, 3, 0.5))
    ball.keyframe_insert("location", frame=1)
    ball.location = (3, 80, 0.5)
    ball.keyframe_insert("location", frame=3)
    scene.frame_start, scene.frame_end = 1, 3
    use_engine(scene, backend="cpu", render_supersampling=1)
    floor_pixel = (30, 10)  # row, column: on the floor, away from the ball's path
    for persistent in (False, True):
        scene.render.use_persistent_data = persistent
        _exr_output(scene, tmp_dir / f"steady{int(persistent)}_")
        assert bpy.ops.render.render(animation=True) == {"FINISHED"}
        images = [_exr_rgba(p) for p in sorted(tmp_dir.glob(f"steady{int(persistent)}_*.exr"))]
        assert len(images) == 3
        values = [float(image[floor_pixel][0]) for image in images]
        assert values[0] > 0.05 and values[0] == values[1] == values[2], (persistent, values)
    scene.frame_set(3)
    floor.scale = (40, 40, 0.1)  # the scene changed: a still is lit by it as it is now
    still = reference(scene, samples_per_axis=1)[1]
    assert bpy.ops.render.render() == {"FINISHED"}
    got = _last_final(scene)["scene"].light.intensity
    assert got == still.light.intensity, (got, still.light.intensity)


def check_a_fixed_light_distance_lights_every_chunk_alike(tmp_dir) -> None:
    """A render farm renders an animation in chunks, each a render job of its own: measured at each
    job's first frame, the light of a chunk starting at frame 3 (the ball far away) differs from
    the light of frames 1-3 rendered in one job. Light Distance measured at frame 1 (Measure) and
    kept in the scene: a chunk of frames 2-3 is lit as the one job lit them, and its frame 3 is
    bvhlab.render of frame 3 exported with that distance; the sidebar's export takes it too.
    Measure refuses a scene without a light."""
    scene = harness.empty_scene((48, 36))
    harness.add_camera((0, -10, 6), (0, 0, 0), lens=30)
    lamp = harness.add_point_light((0, 0, 5))
    harness.add_box("Floor", (0, 0, -0.05), scale=(12, 12, 0.1))
    ball = harness.add_box("Ball", (3, 3, 0.5))
    ball.keyframe_insert("location", frame=1)
    ball.location = (3, 80, 0.5)
    ball.keyframe_insert("location", frame=3)
    use_engine(scene, backend="cpu", render_supersampling=1)
    floor_pixel = (30, 10)  # row, column: on the floor, away from the ball's path

    def chunk(first: int, last: int, name: str) -> list[np.ndarray]:
        scene.frame_start, scene.frame_end = first, last
        _exr_output(scene, tmp_dir / f"{name}_")
        assert bpy.ops.render.render(animation=True) == {"FINISHED"}
        return [_exr_rgba(p) for p in sorted(tmp_dir.glob(f"{name}_*.exr"))]

    assert scene.bvhlab.light_distance == 0.0  # measured by default
    whole = chunk(1, 3, "whole")
    late = chunk(3, 3, "late")
    assert len(whole) == 3 and len(late) == 1
    lit = float(whole[0][floor_pixel][0])
    assert lit > 0.05 and float(whole[2][floor_pixel][0]) == lit
    assert float(late[0][floor_pixel][0]) < 0.5 * lit, "a chunk measured at its own first frame is lit otherwise"

    scene.frame_set(1)
    assert bpy.ops.bvhlab.measure_light_distance() == {"FINISHED"}
    distance = scene.bvhlab.light_distance
    assert distance > 0.0
    fixed = chunk(2, 3, "fixed")
    assert len(fixed) == 2
    assert [float(image[floor_pixel][0]) for image in fixed] == [lit, lit]
    scene.frame_set(3)
    exported = export_scene(bpy.context, light_distance=distance)
    compare_images(fixed[1], reference(scene, samples_per_axis=1, exported=exported)[0], "cpu")
    from bvhlab.blender.light import intensity_from_watts

    sidebar = harness.addon().operator_support.export_scene(bpy.context, require_camera=True)  # its Render's
    assert sidebar.light.intensity == intensity_from_watts(1000.0, distance)

    lamp.hide_render = lamp.hide_viewport = True  # no light to measure from: refused, the distance kept
    try:
        bpy.ops.bvhlab.measure_light_distance()
    except RuntimeError as error:  # the operator's ERROR report
        assert "the scene has no visible light" in str(error), error
    else:
        raise AssertionError("Measure did not refuse a scene without a light")
    assert scene.bvhlab.light_distance == distance


def check_command_line_frames(tmp_dir) -> None:
    """A real Blender binary: `blender -b moving_ball.blend -E BVHLAB_WHITTED -o ... -F OPEN_EXR -f 1
    -a` in a child process with the installed extension enabled by --addons: frame 1, then the
    animation (frame 1 again, 2, 3): three files, each equal to bvhlab.render of its frame's export."""
    import os
    import subprocess

    blend = harness.SCENES_DIR / harness.scenes_index()["moving_ball"]["file"]
    command = [
        bpy.app.binary_path,
        "--background",
        "--factory-startup",
        str(blend),
        "--addons",
        harness._addon_module,
        "--engine",
        ENGINE,
        "--render-output",
        str(tmp_dir / "cli_####"),
        "--render-format",
        "OPEN_EXR",
        "--python-expr",
        _CLI_SETUP,
        "--render-frame",
        "1",
        "--render-anim",
    ]
    done = subprocess.run(command, capture_output=True, text=True, timeout=600, env=dict(os.environ))
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-3000:]
    files = sorted(p.name for p in tmp_dir.glob("cli_*.exr"))
    assert files == ["cli_0001.exr", "cli_0002.exr", "cli_0003.exr"], (files, done.stdout[-2000:])
    scene = harness.open_scene("moving_ball")
    use_engine(scene, backend="auto", render_supersampling=1)
    first_light = None
    for frame in (1, 2, 3):
        scene.frame_set(frame)
        exported = _with_light_of(export_scene(bpy.context), first_light)  # -a keeps frame 1's light
        first_light = first_light or exported.light
        oracle = reference(scene, samples_per_axis=1, exported=exported)[0]
        compare_images(_exr_rgba(tmp_dir / f"cli_{frame:04d}.exr"), oracle, _auto_backend())


#: Run by the child Blender before it renders: lossless EXR output (the file's own settings are PNG).
_CLI_SETUP = (
    "import bpy; s = bpy.context.scene.render.image_settings; "
    "s.exr_codec, s.color_depth, s.color_mode = 'NONE', '32', 'RGBA'"
)


def _auto_backend() -> str:
    return harness.addon().engine.tracer.open_tracer("auto").backend
