"""The render engine's Rendered viewport without a window: the camera it traces for a region
(against Blender's own projection) and its worker thread (levels, the final image against
bvhlab.render, Esc during a build). The add-on must be enabled."""

from __future__ import annotations

import math
from importlib import import_module

import bpy
import harness
import numpy as np
from checks_engine import compare_images

import bvhlab


def _engine_module(name: str):
    from importlib import import_module

    return import_module(f"{harness.addon().__name__}.engine.{name}")


def _camera_matrices(scene, width: int, height: int):
    """view_matrix and window_matrix of the scene camera, as a viewport looking through it has them."""
    depsgraph = bpy.context.evaluated_depsgraph_get()
    camera = scene.camera.evaluated_get(depsgraph)
    window = camera.calc_matrix_camera(depsgraph, x=width, y=height)
    return np.array(camera.matrix_world.inverted()), np.array(window)


def project_view(points: np.ndarray, view, width: int, height: int) -> np.ndarray:
    """Image pixel coordinates (x right, y up, origin at the bottom left) of world points seen by a
    bvhlab.View traced at width × height: its image plane (2 tan(fov_y / 2) high at unit distance,
    or ortho_scale along the larger side; aspect times as wide; shifted by fractions of the larger
    side), written here from the View's documented conventions, not taken from the tracer."""
    position, forward, up = (np.array(v, np.float64) for v in (view.position, view.forward, view.up))
    forward /= np.linalg.norm(forward)
    right = np.cross(forward, up)
    right /= np.linalg.norm(right)
    true_up = np.cross(right, forward)
    aspect = view.aspect or width / height
    d = points - position
    x, y = d @ right, d @ true_up
    if view.projection == "orthographic":
        larger = view.ortho_scale
        plane_h = larger if aspect < 1 else larger / aspect
    else:
        x, y = x / (d @ forward), y / (d @ forward)
        plane_h = 2 * math.tan(math.radians(view.fov_y) / 2)
        larger = plane_h * max(aspect, 1.0)
    x, y = x - view.shift_x * larger, y - view.shift_y * larger
    return np.stack([(x / (plane_h * aspect) + 0.5) * width, (y / plane_h + 0.5) * height], -1)


def check_view_frustum() -> None:
    """Where a world point lands in the region by Blender's own projection (window @ view) is
    where the traced image, drawn at the frustum's rectangle, shows it: centred, with lens shift
    (an off-centre projection), orthographic, and in a portrait region; the clipping planes are
    the camera's."""
    view_camera = _engine_module("view_camera")
    scene = harness.boxes_scene()
    cam = scene.camera.data
    cam.clip_start, cam.clip_end = 0.5, 40.0
    points = np.random.default_rng(4).uniform(-2, 2, (200, 3)) + (0, 0.5, 1)
    errors = []
    cases = (((0, 0), "PERSP", (320, 200)), ((0.2, -0.1), "PERSP", (320, 200)), ((0.1, 0.05), "ORTHO", (320, 200)))
    for shift, kind, (width, height) in (*cases, ((0.1, 0.2), "PERSP", (150, 260)), ((-0.1, 0.1), "ORTHO", (150, 260))):
        cam.type, (cam.shift_x, cam.shift_y), cam.ortho_scale = kind, shift, 6.0
        view, window = _camera_matrices(scene, width, height)
        frustum = view_camera.view_frustum(view, window, width, height)
        clip = (window @ view @ np.c_[points, np.ones(len(points))].T).T
        blender_px = (clip[:, :2] / clip[:, 3:] + 1) / 2 * (width, height)
        ours = project_view(points, frustum.camera(), frustum.width, frustum.height)
        error = np.abs(ours - blender_px).max()
        errors.append(f"{kind} shift {shift} {width}×{height}: {error:.2g} px")
        assert error < 1e-3, (shift, kind, error)
        assert (frustum.width, frustum.height) == (width, height) and frustum.draw_rect == (0, 0, width, height)
        camera = frustum.camera()
        assert math.isclose(camera.clip_start, 0.5, rel_tol=1e-5) and math.isclose(camera.clip_end, 40, rel_tol=1e-5)
    cam.type, cam.shift_x, cam.shift_y = "PERSP", 0.0, 0.0
    print("view frustum against Blender's projection:", "; ".join(errors))


def check_view_frustum_clip_range() -> None:
    """The clip range of the camera the viewport traces is Blender's own, also where the float32
    window matrix no longer holds the far plane (clip_end / clip_start past ~1e5: read from the
    matrix, 10,000 came out 8,389, and 1e6 as -inf, which blanked the viewport: a helper's probe);
    a clip range that is not the matrix's is not taken, and without one a far plane the matrix
    lost is left open."""
    view_camera = _engine_module("view_camera")
    scene = harness.boxes_scene()
    cam = scene.camera.data
    cam.type = "PERSP"
    for start, end in ((0.01, 1e4), (0.001, 1e4), (0.01, 1e5), (0.01, 1e6), (0.001, 1e5), (1e-4, 1e8)):
        cam.clip_start, cam.clip_end = start, end
        view, window = _camera_matrices(scene, 320, 200)
        camera = view_camera.view_frustum(view, window, 320, 200, (cam.clip_start, cam.clip_end)).camera()
        assert (camera.clip_start, camera.clip_end) == (cam.clip_start, cam.clip_end), (start, end, camera)
        alone = view_camera.view_frustum(view, window, 320, 200).camera()  # no source: never fails
        assert alone.clip_end > alone.clip_start >= 0 and math.isclose(alone.clip_start, start, rel_tol=1e-3)
        other = view_camera.view_frustum(view, window, 320, 200, (start * 3, end)).camera()  # not the matrix's
        assert math.isclose(other.clip_start, start, rel_tol=1e-3), (start, end, other)
    cam.clip_start, cam.clip_end = 0.1, 100.0


def check_orthographic_view_fitted_to_the_scene() -> None:
    """A user orthographic view puts its near plane clip_end / 2 behind the eye: the viewport's
    rays start a little before the scene's bounds instead (Clip End 1e8 lost every object, 1e6
    tore silhouettes: a helper's probe). The picture equals that of the same view unfitted with
    Clip End 1,000 (the default: its rays start 500 behind the eye) but for pixels on silhouettes
    (float32 rounding of the two starts); a scene wholly beyond the far plane keeps the view (a
    negative clip_end was made: the viewport stopped on the error)."""
    import dataclasses

    from bvhlab.library import procedural

    view_camera = _engine_module("view_camera")
    scene = bvhlab.Scene(triangles=procedural.torus_knot(4000))
    bvh = bvhlab.build(scene)
    forward = np.array([0.3, 1.0, -0.4]) / np.linalg.norm([0.3, 1.0, -0.4])
    base = bvhlab.View(position=tuple(-8 * forward), forward=tuple(forward), projection="orthographic", ortho_scale=4.0)

    def pulled(clip_end: float):  # as view_frustum makes a user orthographic view's
        return dataclasses.replace(base, position=tuple(-8 * forward - forward * clip_end / 2), clip_end=clip_end)

    def image(view):
        return bvhlab.render(scene, bvh, 96, 64, backend="cpu", camera=view)[0]

    unfitted = image(pulled(1e3))
    for clip_end in (1e3, 1e6, 1e8):
        fitted = view_camera.ViewFrustum(pulled(clip_end), 96, 64, (0, 0, 96, 64)).fitted(scene.world_bounds)
        assert np.linalg.norm(fitted.position) < 10, fitted.position
        differ = (np.abs(image(fitted) - unfitted).max(-1) > 1e-3).mean()
        assert differ <= 0.005, (clip_end, differ)
    lost = image(pulled(1e8))
    assert (np.abs(lost - unfitted).max(-1) > 1e-3).mean() > 0.05, "the unfitted view far away should differ"
    near_only = dataclasses.replace(base, clip_end=2.0)  # the knot lies 6-10 ahead: beyond the far plane
    frustum = view_camera.ViewFrustum(near_only, 96, 64, (0, 0, 96, 64))
    assert frustum.fitted(scene.world_bounds) == near_only
    assert frustum.fitted(lambda: None) == near_only


def _wait(condition, timeout: float = 120.0, what: str = "the viewport worker"):
    import time

    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        value = condition()
        if value:
            return value
        time.sleep(0.02)
    raise AssertionError(f"{what} did not get there within {timeout} s")


def _session_for(
    scene, width: int, height: int, samples_per_axis: int, overlay=None, counter=None, film_transparent=False
):
    """A viewport worker fed the way view_update / view_draw feed it, looking through the scene
    camera; returns (session, request)."""
    from bvhlab.blender import LiveScene

    viewport, view_camera = _engine_module("viewport"), _engine_module("view_camera")
    live = LiveScene("visible", require_camera=False)
    report = live.sync(bpy.context.evaluated_depsgraph_get(), scene, bpy.context.view_layer)
    view, window = _camera_matrices(scene, width, height)
    frustum = view_camera.view_frustum(view, window, width, height)
    settings = bvhlab.RenderOptions(
        samples_per_axis=samples_per_axis,
        max_depth=5,
        overlay_depth=overlay,
        traversal="stackless",
        traversal_counters=counter is not None,
        film_transparent=film_transparent,
    )
    tree = _trees().TreeKey(scene.session_uid, "visible", bvhlab.BuildConfig())
    request = viewport.ViewRequest(frustum, settings, "cpu", tree, budget_ms=5.0, counter=counter)
    session = viewport.ViewportSession()
    session.set_scene(live.scene, report)
    session.request(request)
    return session, request, live


def _oracle(live, request, width: int, height: int, **options):
    """bvhlab.render on the CPU of what a _session_for worker traces at 2×2 samples: the same scene,
    tree and camera, as the request's options say (`options`: those that differ from the defaults)."""
    image, _ = bvhlab.render(
        live.scene,
        _tree_of(request).bvh,
        width,
        height,
        backend="cpu",
        camera=request.frustum.camera(),
        samples_per_axis=2,
        max_depth=5,
        traversal="stackless",
        **options,
    )
    return image


def _trees():
    return import_module(harness.addon().__name__ + ".trees")


def _tree_of(request):
    """The SceneTree of the add-on's one cache the viewport traces with."""
    return _trees().cache.tree(request.tree)


def check_viewport_worker_levels() -> None:
    """The viewport's worker, fed one scene and one view: a preview at a fraction of the resolution,
    then full resolution, then 2×2 samples; the last equals bvhlab.render from the view's camera
    (boxes of depths 8-9 traced in). Frame times printed, not asserted. The levels are taken as the
    worker publishes them (sampled every 20 ms, a fast machine's full frame was missed: an audit)."""
    scene = harness.open_scene("atrium")
    session_class, levels, session = _engine_module("viewport").ViewportSession, [], None

    def publish(self, frame) -> None:
        levels.append((frame.level, frame.image.shape[:2], round(frame.timings["trace_ms"], 1)))
        publish.__wrapped__(self, frame)

    publish.__wrapped__ = session_class._publish
    session_class._publish = publish  # until the session is closed: the worker looks it up each frame
    try:
        session, request, live = _session_for(scene, 240, 160, samples_per_axis=2, overlay=(8, 9))

        def refined():
            frame = session.latest_frame()
            return frame if frame is not None and frame.level == "refined" else None

        frame = _wait(refined)
        compare_images(frame.image, _oracle(live, request, 240, 160, overlay_depth=(8, 9)), "cpu")
        names = [name for name, _, _ in levels]
        assert names[-2:] == ["full", "refined"] and set(names) <= {"preview", "full", "refined"}, levels
        if "preview" in names:
            assert levels[names.index("preview")][1][1] < 240
        print(f"viewport worker levels on the atrium at 240×160 (level, size, trace ms): {levels}")
    finally:
        if session is not None:
            session.close()
        session_class._publish = publish.__wrapped__


def check_viewport_film_transparent() -> None:
    """Film ▸ Transparent in the Rendered viewport, as in Cycles': the scene's settings ask for it
    (render_options(viewport=True)), and the worker's refined frame is bvhlab.render's with
    film_transparent, alpha and all (the sky's pixels 0: display.py draws premultiplied, so the
    viewport's background shows there)."""
    scene = harness.open_scene("whitted")
    updated: list = []  # setting it tags the scene: Blender calls view_update and redraws

    def note(blender_scene, depsgraph):
        updated.extend(u.id.original for u in depsgraph.updates if isinstance(u.id, bpy.types.Scene))

    bpy.context.view_layer.update()
    bpy.app.handlers.depsgraph_update_post.append(note)
    try:
        scene.render.film_transparent = True
        bpy.context.view_layer.update()
    finally:
        bpy.app.handlers.depsgraph_update_post.remove(note)
    assert scene in updated
    assert scene.bvhlab.render_options(viewport=True).film_transparent
    session, request, live = _session_for(scene, 96, 64, samples_per_axis=2, film_transparent=True)
    try:
        frame = _wait(lambda: (f := session.latest_frame()) is not None and f.level == "refined" and f or None)
        compare_images(frame.image, _oracle(live, request, 96, 64, film_transparent=True), "cpu")
        alpha = frame.image[..., 3]
        assert (alpha == 0).any() and (alpha == 1).any(), np.unique(alpha)
    finally:
        session.close()


def check_viewport_counter_display() -> None:
    """The viewport showing a counter (primitive tests, auto range; then box hits over 0..4): the
    full-resolution frame is the heat ramp of the CPU reference's counter over the range the
    frame reports, and the auto range is 0 to the 99th percentile; the frame's histogram is
    bvhlab.histogram's of the same counts."""
    from bvhlab import counters, histogram, palette

    counter_view = _engine_module("counter_view")
    scene = harness.open_scene("whitted")
    for view in (counter_view.CounterView("prim_tests", None), counter_view.CounterView("box_hits", (0.0, 4.0))):
        session, request, live = _session_for(scene, 64, 48, samples_per_axis=1, counter=view)
        try:
            frame = _wait(lambda s=session: _at_level(s, "full"))
            job = bvhlab.Renderer("cpu").start(
                live.scene, _tree_of(request).bvh, 64, 48, camera=request.frustum.camera(), options=request.settings
            )
            job.run()
            plane = counters.counter_plane(job.result(color=False, depth=False, counters=True).counters, view.counter)
            lo, hi = frame.timings["counter_range"]
            assert (lo, hi) == (counters.auto_range(plane) if view.value_range is None else view.value_range)
            np.testing.assert_array_equal(frame.image, palette.heat_image(plane, lo, hi))
            assert frame.timings["counter"] == view.counter and len(np.unique(plane)) > 2
            hist = frame.timings["counter_histogram"]  # the sidebar's histogram of the frame's counts
            expected = histogram.counter_histogram(plane, view.counter, view.value_range, counter_view.SIDEBAR_BINS)
            assert hist.pixels == 64 * 48 and hist.counts.tolist() == expected.counts.tolist()
        finally:
            session.close()


def _at_level(session, level: str):
    frame = session.latest_frame()
    return frame if frame is not None and frame.level == level else None


def check_viewport_build_cancels() -> None:
    """Esc (session.cancel) during the build of a million triangles stops it (no tree, a status
    that says so) and nothing is traced until the scene changes; then it builds and traces."""
    scene = harness.open_scene("suzanne_1m")
    session, request, live = _session_for(scene, 64, 48, samples_per_axis=1)
    try:
        _wait(lambda: session.status().startswith("Building BVH"), what="the build")
        session.cancel()
        _wait(lambda: not session.busy, what="the cancelled build")
        assert _tree_of(request).bvh is None and session.latest_frame() is None
        assert session.status().startswith("Cancelled"), session.status()
        session.set_scene(live.scene, None)  # what view_update does after an edit
        frame = _wait(lambda: _at_level(session, "full"), what="the build after the edit")
        assert _tree_of(request).bvh is not None and frame.image.shape[:2] == (48, 64)
    finally:
        session.close()


class _NotingReads:
    """scene.bvhlab as the engine's code sees it, noting the name of every setting it reads (its
    methods, build_config and render_options, run on this stand-in, so their reads are noted too)."""

    def __init__(self, settings):
        self._settings, self.names = settings, set()

    def __getattr__(self, name):
        method = getattr(type(self._settings), name, None)
        if callable(method):
            return method.__get__(self)
        self.names.add(name)
        return getattr(self._settings, name)


def viewport_settings(scene) -> set[str]:
    """The scene.bvhlab settings the Rendered viewport depends on: those the engine's own
    view_request reads (what view_draw hands the worker) for a region looking through the camera."""
    from types import SimpleNamespace

    view, window = _camera_matrices(scene, 64, 48)
    region_data = SimpleNamespace(
        view_matrix=view, window_matrix=window, is_perspective=True, view_distance=8.0, view_perspective="PERSP"
    )
    context = SimpleNamespace(region=SimpleNamespace(width=64, height=48), region_data=region_data, space_data=None)
    noting = _NotingReads(scene.bvhlab)
    _engine_module("view_request").view_request(context, SimpleNamespace(bvhlab=noting, session_uid=scene.session_uid))
    # not id_data: the scene itself (Film ▸ Transparent is read through it), whose own render
    # settings Blender tags when set
    return {name for name in noting.names if name in scene.bvhlab.bl_rna.properties}


def _another_value(settings, name: str):
    """A valid value of the setting `name` other than its current one."""
    prop, value = settings.bl_rna.properties[name], getattr(settings, name)
    if getattr(prop, "is_array", False):  # a colour: move each channel within its range
        return tuple(x + 0.25 if x + 0.25 <= prop.hard_max else x - 0.25 for x in value)
    if prop.type == "ENUM":
        return next(item.identifier for item in prop.enum_items if item.identifier != value)
    if prop.type == "BOOLEAN":
        return not value
    if prop.type in ("INT", "FLOAT"):
        return value + 1 if value + 1 <= prop.hard_max else value - 1
    raise AssertionError(f"{name}: a {prop.type} setting; add how to change it")


def check_viewport_settings_update() -> None:
    """Setting, from a script, any scene.bvhlab setting the Rendered viewport depends on tags the
    scene in the depsgraph: what makes Blender call the engine's view_update and redraw Rendered
    viewports (a property without an update function is not updated at all when a script sets it;
    the user's clicks always are). The settings are the ones the engine's own code reads."""
    scene = harness.boxes_scene()
    scene.bvhlab.overlay_show = True  # so that the boxes' settings are read too
    names = viewport_settings(scene)
    assert {"render_mode", "render_supersampling", "method", "overlay_depth_max"} <= names, names
    updated: list = []

    def note(blender_scene, depsgraph):
        updated.extend(u.id.original for u in depsgraph.updates if isinstance(u.id, bpy.types.Scene))

    bpy.context.view_layer.update()
    bpy.app.handlers.depsgraph_update_post.append(note)
    try:
        silent = []
        for name in sorted(names):
            updated.clear()
            setattr(scene.bvhlab, name, _another_value(scene.bvhlab, name))
            bpy.context.view_layer.update()
            if scene not in updated:
                silent.append(name)
    finally:
        bpy.app.handlers.depsgraph_update_post.remove(note)
    assert not silent, f"setting these from a script leaves the Rendered viewport as it was: {silent}"
    print(f"viewport settings, each tagging the scene when set: {sorted(names)}")
