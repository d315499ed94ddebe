"""Final renders (F12, bpy.ops.render.render, `blender -b file -f N` / `-a`) into Blender's Render
Result: Combined, Depth and heatmap passes, progress and Esc the way Blender shows them.

`sync` runs in RenderEngine.update (Blender holds the scene for it); `render` in RenderEngine.render.
An engine instance lives for one render, or for as long as Blender keeps it: with Render ▸
Performance ▸ Persistent Data on, the same instance (and depsgraph) serves every frame of an
animation and every later F12, so only what the depsgraph reports as changed is read again.
"""

from __future__ import annotations

import time
import warnings
from dataclasses import replace

import bpy

from bvhlab.overlay_levels import traced_cap_note

from .. import state
from ..trees import cache, key_of, update_config
from . import passes
from .border import final_frame
from .settings import backend, final_threads, fixed_light_distance
from .tracer import TraceCancelled, open_tracer
from .unrendered import unrendered_features

#: Progress (RenderEngine.update_progress) at the start of each stage.
BUILD_START, TRACE_START = 0.05, 0.35


#: A render job's light calibration (LiveScene.light_distance) by scene name: measured at its first
#: frame, kept for an animation's others (without Persistent Data each frame has an engine and a
#: LiveScene of its own); cleared when a render job starts (render_init: forget_job_light). Not
#: RenderEngine.is_animation: with Persistent Data an engine made for an animation keeps it set
#: for the F12 stills after it.
_JOB_LIGHT: dict[str, float] = {}


@bpy.app.handlers.persistent
def forget_job_light(*_args) -> None:
    _JOB_LIGHT.clear()


class FinalRender:
    """One engine instance's final-render state: the scene it keeps between frames."""

    def __init__(self):
        from bvhlab.blender import LiveScene

        self.live = LiveScene("visible", require_camera=True, allow_empty=True)
        self.error: str | None = None
        self.report = None
        self.notes: list[str] = []

    def sync(self, engine, depsgraph) -> None:
        """Export what changed since the last frame (all of it the first time); the frames of a
        render job are lit by the scene's fixed calibration of the light, else by its first
        frame's. The camera is the one `engine` renders through (a Sequencer strip's camera
        override) at the size it renders (another scene's, where that scene's compositor renders
        this one), as Cycles frames them."""
        from bvhlab.blender import ExportError, ExportWarning

        self.live.camera_object, self.live.frame_size = engine.camera_override, _frame_size(engine)
        name = depsgraph.scene.name_full  # a linked scene of the same name is another
        fixed = fixed_light_distance(depsgraph.scene)
        # None: measured (Persistent Data kept the last)
        self.live.light_distance = fixed if fixed is not None else _JOB_LIGHT.get(name)
        self.error, self.notes = None, []
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", ExportWarning)
            try:
                self.report = self.live.sync(depsgraph)
            except ExportError as error:
                self.error = str(error)
            except Exception as error:  # a bug: said in render(), never raised into Blender's update
                from ..operator_support import describe_error

                self.error = describe_error(error)
        if self.live.light_distance is not None and fixed is None:
            _JOB_LIGHT.setdefault(name, self.live.light_distance)
        self.notes = [str(w.message) for w in caught if issubclass(w.category, ExportWarning)]

    def render(self, engine, depsgraph) -> None:
        blender_scene = depsgraph.scene
        if self.error is not None:
            engine.report({"ERROR"}, f"bvhlab: {self.error}")
            return
        for note in self.notes:
            engine.report({"WARNING"}, f"bvhlab: {note}")
        try:
            self._render(engine, depsgraph, blender_scene)
        except Exception as error:  # reported, never raised into Blender's render thread
            import bvhlab

            if isinstance(error, (bvhlab.BuildCancelled, TraceCancelled)):
                engine.update_stats("", "Cancelled")
                return
            if not isinstance(error, (ValueError, RuntimeError, OSError)):
                import traceback

                traceback.print_exc()
            engine.report({"ERROR"}, f"bvhlab: {error}")

    def _render(self, engine, depsgraph, blender_scene) -> None:
        key = state.key(blender_scene)
        scene = self.live.scene
        tracer = open_tracer(backend(blender_scene))
        frame = final_frame(blender_scene.render, engine.resolution_x, engine.resolution_y)
        # before the build and before Blender allocates the Render Result (issue 39: a huge F12 was
        # refused only after gigabytes of passes)
        tracer.check_size(frame.width, frame.height)
        settings = blender_scene.bvhlab.render_options()
        # the counter passes (issue 35); the heatmap pass too where the walk keeps counters, so that
        # its box tests are the walks' whole (a render that keeps none stops a primary ray at the
        # overlay's line; the wide walk keeps only the heatmap's cost)
        heat = passes.heatmap_wanted(depsgraph.view_layer) and settings.traversal != "wide"
        if passes.counters_wanted(depsgraph.view_layer) or heat:
            settings = settings.replace(traversal_counters=True)
        # Traversal Auto: the heatmap pass counts the binary tree's box tests, as the heatmap mode
        settings = settings.for_backend(
            tracer.backend == "cpu", counts_shown=passes.heatmap_wanted(depsgraph.view_layer)
        )
        shown = settings  # with the overlay: each view's camera decides for its own (a multi-view render)
        camera, settings, unrendered = self._camera(depsgraph, scene.camera, frame, settings, engine.camera_override)
        for note in unrendered:
            engine.report({"WARNING"}, f"bvhlab: {note}")
        update = self._tree(engine, blender_scene)
        capped = traced_cap_note(update.bvh, settings)
        if capped:  # said as the sidebar says it under its boxes
            engine.report({"WARNING"}, f"bvhlab: the box overlay shows {capped}")
        if engine.test_break():
            engine.update_stats("", "Cancelled")
            return
        layer = depsgraph.view_layer.name
        views = render_views(engine, blender_scene.render, layer)  # [None]: one view; else each eye or view by name
        engine.update_progress(TRACE_START)
        threads = final_threads(blender_scene)
        jobs = []
        for index, view in enumerate(views):
            if view is not None:  # the view's camera: an eye's offset and convergence (Stereoscopy)
                engine.active_view_set(view)
                view_camera = self._view_camera(engine, depsgraph, view, frame)
                # a view's panorama draws no boxes, another view's camera may (said once)
                settings = _overlay_for(view_camera, shown, unrendered, engine)
            else:
                view_camera = camera
            job = tracer.start(
                scene,
                update.bvh,
                view_camera,
                frame.width,
                frame.height,
                settings,
                threads,
                heat=passes.heatmap_wanted(depsgraph.view_layer),
            )
            jobs.append(job)
            on, named = job.timings["device"], "" if view is None else f" ({view})"
            engine.update_stats(
                "", f"Tracing {frame.width} × {frame.height}{named}, {settings.samples} samples per pixel on {on}"
            )
            cancelled = self._trace(engine, job, layer, view, (index, len(views)))
            if cancelled:
                break
        record = {
            **_trace_record(update, jobs, frame),
            "views": views[: len(jobs)],
            "sync": self.report,
            "scene": scene,  # the exported bvhlab.Scene rendered (the checks read it)
            "totals": self.live.totals,
            "cancelled": cancelled,
            "unrendered": unrendered,
            "overlay_note": capped,
        }
        with state.lock:
            state.last_final[key] = record
        if cancelled:  # as Cycles says it; the samples finished so far are in the Render Result
            engine.update_stats("", f"Cancelled | {job.samples_done} of {settings.samples} samples per pixel")
            return
        engine.update_progress(1.0)
        engine.update_stats("", _summary(record))

    @staticmethod
    def _camera(depsgraph, camera, frame, settings, camera_object=None):
        """The scene camera for this frame's part (the render border), the settings, and what of the
        scene's settings bvhlab does not render, in words (said, never silently left out);
        `camera_object` the one rendered through where it is not the scene's (a strip's)."""
        unrendered = unrendered_features(depsgraph, camera_object)
        if _draws_no_boxes(camera) and settings.overlay_depth is not None:
            unrendered.append(_no_boxes_note(camera))
            settings = settings.replace(overlay_depth=None)
        return (camera if frame.whole else replace(camera, region=frame.region)), settings, unrendered

    @staticmethod
    def _view_camera(engine, depsgraph, view: str, frame):
        """The camera of one view of a stereo or multi-view render (its view active in `engine`),
        framed as the scene camera is: the border's part of it."""
        from bvhlab.blender import ExportError
        from bvhlab.blender.camera import StereoView, gather_camera, view_camera_object

        blender_scene = depsgraph.scene
        camera_object = view_camera_object(blender_scene, view, engine.camera_override)
        evaluated = camera_object.evaluated_get(depsgraph)
        # no spherical stereo (bl_use_spherical_stereo off): a panorama's eyes are two panoramas
        # from the eyes' positions, as Blender frames them for such an engine
        stereo = StereoView(
            camera_object,
            engine.camera_model_matrix(evaluated, use_spherical_stereo=False),
            engine.camera_shift_x(evaluated, use_spherical_stereo=False),
        )
        try:
            camera = gather_camera(blender_scene, depsgraph, view=stereo, size=_frame_size(engine))
        except ExportError as error:
            raise ValueError(f"view '{view}': {error}") from None
        return camera if frame.whole else replace(camera, region=frame.region)

    def _trace(self, engine, job, layer_name: str, view: str | None = None, part: tuple[int, int] = (0, 1)) -> bool:
        """Traces into Blender's Render Result (the view's, where `view` is named) in sample passes
        (1, 2, 4, ... samples per pixel), writing the passes after each, so that Esc keeps the
        samples finished so far, as Cycles does. `part`: this view's index and the number of views
        (the progress bar's share). Returns True when Esc stopped it."""
        width, height = job.size
        result = engine.begin_result(0, 0, width, height, layer=layer_name, view=view or "")
        cancelled = False
        try:
            layer = result.layers[0]
            depth, heat = (layer.passes.get(name) is not None for name in (passes.DEPTH, passes.HEATMAP))
            counters = job.keeps_counters and any(
                layer.passes.get(n) is not None for n in passes.counter_passes().values()
            )
            total = job.samples_per_pixel
            for target in sample_passes(total):
                try:
                    job.run(target, cancelled=engine.test_break)
                except TraceCancelled:
                    cancelled = True
                passes.write_all(layer, job.images(depth=depth, heat=heat, counters=counters))
                engine.update_result(result)
                if cancelled:
                    break
                done = (part[0] + target / total) / part[1]
                engine.update_progress(TRACE_START + (1.0 - TRACE_START) * done)
                engine.update_stats("", f"Sample {target}/{total}")
        finally:
            engine.end_result(result)
        return cancelled

    def _tree(self, engine, blender_scene):
        """The scene's tree from the add-on's one cache (trees.py), made to fit: one the sidebar's
        Build or the viewport made over the same geometry is used as it is. An instanced scene
        (Blender's instancing, issue 34) renders through its two-level tree, never flattened; when
        only instances moved, only its TLAS is made again; a mesh that moved or was edited has its
        tree updated with the scene's update policy."""
        scene = self.live.scene
        key = key_of(blender_scene, scope="visible")  # a render shows every visible object
        tree = cache.tree(key)
        engine.update_progress(BUILD_START)
        engine.update_stats("", f"Building BVH ({key.config.method})")

        def progress(fraction: float) -> bool:
            engine.update_progress(BUILD_START + (TRACE_START - BUILD_START) * fraction)
            return not engine.test_break()

        started = time.perf_counter()
        refittable = self.report is not None and self.report.refittable
        update = tree.update(
            scene, refittable, progress, threads=final_threads(blender_scene), policy=update_config(blender_scene)
        )
        if update.action != "kept":
            engine.update_stats("", f"BVH {update.action} in {(time.perf_counter() - started) * 1e3:.0f} ms")
            state.rendered_over(tree)
        return update


def _frame_size(engine) -> tuple[int, int]:
    """The frame the engine renders, in pixels (the scene's resolution at its percentage, or the
    size of the scene whose compositor renders this one): what the camera's aspect fits."""
    return engine.resolution_x, engine.resolution_y


def _draws_no_boxes(camera) -> bool:
    """Whether the box overlay cannot be drawn through `camera` (its lines are straight)."""
    return camera.projection in ("equirectangular", "fisheye")


def _no_boxes_note(camera) -> str:
    return f"the box overlay is not drawn through {camera.projection} cameras"


def _overlay_for(camera, settings, unrendered: list, engine):
    """`settings` for a view seen through `camera`: without the overlay where the camera cannot draw
    it, said once (a multi-view render's panorama; the scene camera's is said by _camera)."""
    if settings.overlay_depth is None or not _draws_no_boxes(camera):
        return settings
    note = _no_boxes_note(camera)
    if note not in unrendered:
        unrendered.append(note)
        engine.report({"WARNING"}, f"bvhlab: {note}")
    return settings.replace(overlay_depth=None)


def _trace_record(update, jobs: list, frame) -> dict:
    """What Render Properties ▸ Last Render shows of a final render, and the checks read: the device,
    backend and note of the jobs (one a view; auto renders the wide traversal on the CPU whatever
    the Tracer's backend), their times added up, the samples every view has."""
    timings = jobs[0].timings
    return {
        "device": timings["device"],
        "backend": timings["backend"],
        "note": timings.get("fallback"),
        "tree": update.action,
        "build_ms": update.ms,
        "trace_ms": sum(job.timings["trace_ms"] for job in jobs),
        "total_ms": sum(job.timings["total_ms"] for job in jobs),
        "size": (frame.width, frame.height),
        "frame": frame,
        "samples": min(job.samples_done for job in jobs),
    }


def render_views(engine, render, layer_name: str) -> list[str | None]:
    """The views a render makes, by name, as Cycles asks for them (an empty result's views): the
    eyes of Output ▸ Stereoscopy, the views of a multi-view render; [None] without multi-view."""
    if not render.use_multiview:
        return [None]
    result = engine.begin_result(0, 0, 1, 1, layer=layer_name)
    try:
        names = [v.name for v in result.views]
    finally:
        engine.end_result(result, cancel=True, highlight=False, do_merge_results=False)
    return names or [None]  # one view enabled of a multi-view render: still through its own camera


def sample_passes(total: int) -> list[int]:
    """Samples per pixel after each pass of a final render: doubling from 1 up to `total`."""
    targets, n = [], 1
    while n < total:
        targets.append(n)
        n *= 2
    return [*targets, total]


def _summary(record: dict) -> str:
    parts = [
        f"BVH {record['tree']}" + (f" {record['build_ms']:.0f} ms" if record["tree"] != "kept" else ""),
        f"trace {record['trace_ms']:.0f} ms",
    ]
    if record["overlay_note"]:
        parts.append(f"overlay: {record['overlay_note']}")
    return " | ".join(parts) + f" | {record['device']}"
