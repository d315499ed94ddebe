"""The viewport's Rendered shading: a worker thread that builds the tree and traces the current view,
so Blender's UI thread never waits for either.

The UI thread (RenderEngine.view_update / view_draw) hands over the latest exported scene and the
latest view; the worker always works on the newest of both. For one view it traces in levels:
- "preview": a fraction of the region's resolution chosen so the trace takes about the preview
  budget (from the speed measured on the previous frames), 1 sample per pixel;
- "full": the region's resolution, 1 sample, once the view has stayed still for SETTLE_S;
- "refined": full resolution with n×n samples (only when n > 1).
A new view or scene drops the levels not yet started and stops the level tracing now within one
dispatch (the tracer polls between its bounded dispatches: see tracer.py). A build in progress is
cancelled at once when a newer scene arrives, when the session closes, or by Esc (`cancel`).
"""

from __future__ import annotations

import threading
import time
import traceback
import weakref
from dataclasses import dataclass

from bvhlab.overlay_levels import traced_cap_note

from ..trees import TreeKey, cache
from .counter_view import counter_colors, counter_histogram
from .settings import VIEWPORT_THREADS
from .tracer import TraceCancelled, open_tracer
from .view_camera import ViewFrustum

#: Seconds the view must stay still before the full-resolution level starts.
SETTLE_S = 0.15
#: The coarsest preview: 1/MAX_PREVIEW_DIVISOR of the resolution along each axis.
MAX_PREVIEW_DIVISOR = 8

_sessions: weakref.WeakSet[ViewportSession] = weakref.WeakSet()


@dataclass(frozen=True)
class ViewRequest:
    """Everything a viewport frame depends on besides the scene."""

    frustum: ViewFrustum
    settings: object  # bvhlab.RenderOptions as refined (n×n samples); lower levels use 1 sample
    backend: str
    tree: TreeKey  # the tree of the add-on's one cache (trees.py) the view is traced with
    budget_ms: float
    note: str = ""  # what of the camera the viewport does not show (view_request.camera_view_note)
    update: object = None  # the bvhlab.UpdateConfig a moved or edited mesh's tree is updated with
    counter: object = None  # counter_view.CounterView: a traversal counter instead of the image; None: the image


@dataclass(frozen=True)
class ViewFrame:
    """A traced image (float32 (h, w, 4), row 0 at the top) and how it was made."""

    image: object
    request: ViewRequest
    level: str
    scale: float
    timings: dict
    serial: int


class ViewportSession:
    """One viewport's worker. Methods without a leading underscore are for the UI thread."""

    def __init__(self):
        self._cv = threading.Condition()
        self._scene = None
        self._scene_serial = 0
        self._refittable = True
        self._request: ViewRequest | None = None
        self._request_serial = 0
        self._request_time = 0.0
        self._frame: ViewFrame | None = None
        self._status = "Waiting for the scene"
        self._error: str | None = None
        self._paused = False  # after Esc: until the scene changes
        self._redraw = True
        self._closed = False
        self._busy = False
        self._ms_per_sample = None  # measured trace speed (ms per pixel-sample)
        self._bounds_of: tuple | None = None  # (scene serial, its world bounds): _bounds
        self._failed = False  # the last frame's work raised: a new view tries again
        _sessions.add(self)
        self._thread = threading.Thread(target=self._run, name="bvhlab viewport", daemon=True)
        self._thread.start()

    # -- the UI thread -------------------------------------------------------------------------
    def set_scene(self, scene, report) -> None:
        """A newly exported scene and its LiveScene report (None: unknown changes, the tree is
        built again unless the geometry is equal). A scene change resumes after Esc."""
        with self._cv:
            refittable = report is not None and (not report.geometry or report.refittable)
            self._refittable = self._refittable and refittable
            self._scene, self._error, self._paused, self._failed = scene, None, False, False
            self._scene_serial += 1
            self._cv.notify_all()

    def set_error(self, message: str) -> None:
        with self._cv:
            self._scene, self._frame, self._error = None, None, message
            self._scene_serial += 1
            self._redraw = True
            self._cv.notify_all()

    def request(self, request: ViewRequest) -> None:
        """The view to show; a different one from the last starts again at the preview level."""
        with self._cv:
            if request != self._request:
                self._request, self._request_time = request, time.monotonic()
                self._request_serial += 1
                if self._failed:  # an error of that view (not Esc, not the scene's): this one is tried
                    self._failed, self._paused, self._error = False, False, None
                self._cv.notify_all()

    def latest_frame(self) -> ViewFrame | None:
        with self._cv:
            return self._frame

    def status(self) -> str:
        with self._cv:
            return self._error or self._status

    def take_redraw(self) -> bool:
        """True once after each new frame or status (the redraw timer asks)."""
        with self._cv:
            redraw, self._redraw = self._redraw, False
            return redraw

    @property
    def busy(self) -> bool:
        with self._cv:
            return self._busy

    def cancel(self) -> None:
        """Esc: stop the build in progress and the levels not started; wait for a scene change."""
        with self._cv:
            self._paused, self._failed = True, False  # Esc holds until the scene changes, a view too
            self._status = "Cancelled (Esc): edit the scene to trace again"
            self._redraw = True
            self._cv.notify_all()

    def close(self) -> None:
        with self._cv:
            self._closed = True
            self._cv.notify_all()

    @property
    def closed(self) -> bool:
        return self._closed

    # -- the worker ------------------------------------------------------------------------------
    def _set_status(self, text: str) -> None:
        with self._cv:
            self._status, self._redraw = text, True

    def _job(self):
        """Wait for work; (scene, scene serial, request, request serial, refittable) or None to stop."""
        with self._cv:
            while not self._closed:
                ready = self._scene is not None and self._request is not None and not self._paused
                if ready and (self._frame is None or self._stale()):
                    refittable, self._refittable = self._refittable, True
                    self._busy = True
                    return self._scene, self._scene_serial, self._request, self._request_serial, refittable
                self._busy = False
                self._cv.wait()
            return None

    def _stale(self) -> bool:
        frame = self._frame
        return (
            frame.request != self._request
            or frame.serial != self._scene_serial
            or frame.level != _levels(frame.request, self._ms_per_sample)[-1][0]
        )

    def _current(self, scene_serial: int, request_serial: int) -> bool:
        with self._cv:
            return (
                not self._closed
                and not self._paused
                and scene_serial == self._scene_serial
                and request_serial == self._request_serial
            )

    def _run(self) -> None:
        while True:
            job = self._job()
            if job is None:
                return
            try:
                self._work(*job)
            except Exception as error:  # a worker thread never lets an exception escape
                import bvhlab

                if not isinstance(error, bvhlab.BuildCancelled):
                    traceback.print_exc()
                    with self._cv:
                        self._error, self._redraw = f"bvhlab: {error}", True
                        self._paused = self._failed = True

    def _work(self, scene, scene_serial, request, request_serial, refittable) -> None:
        tracer = open_tracer(request.backend)
        update = self._update_tree(scene, scene_serial, request, request_serial, refittable)
        if update is None:
            return
        capped = traced_cap_note(update.bvh, request.settings)
        camera = request.frustum.fitted(lambda: self._bounds(scene, scene_serial))
        for level, scale, samples_per_axis in _levels(request, self._ms_per_sample):
            if level != "preview" and not self._settled(scene_serial, request_serial):
                return
            if not self._current(scene_serial, request_serial):
                return
            width, height = request.frustum.scaled(scale)
            settings = request.settings.replace(samples_per_axis=samples_per_axis)
            spp = settings.samples
            self._set_status(f"Tracing {level} {width} × {height}" + (f", {spp} spp" if spp > 1 else ""))
            started = time.perf_counter()
            try:
                images, timings = tracer.trace(
                    scene,
                    update.bvh,
                    camera,
                    width,
                    height,
                    settings,
                    threads=VIEWPORT_THREADS,
                    cancelled=lambda: not self._current(scene_serial, request_serial),
                )
            except TraceCancelled:
                return
            image, counter_range = images.color, None
            if request.counter is not None and images.counters is not None:
                image, counter_range = counter_colors(images.counters, request.counter)
            wall_ms = (time.perf_counter() - started) * 1e3
            self._ms_per_sample = timings["trace_ms"] / (width * height * spp)
            frame_timings = {
                "level": level,
                "width": width,
                "height": height,
                "spp": spp,
                "trace_ms": timings["trace_ms"],
                "overlay_ms": timings.get("overlay_ms", 0.0),
                "total_ms": timings["total_ms"],
                "frame_ms": wall_ms,
                "tree": update.action,
                "build_ms": update.ms,
                "device": timings["device"],  # the job's: auto renders the wide traversal on the CPU
                "note": timings.get("fallback"),
                "overlay_note": capped,
                "latency_ms": (time.monotonic() - self._request_time) * 1e3,
                "counter": request.counter.counter if counter_range else None,
                "counter_range": counter_range,  # what the panel's legend shows
                "counter_histogram": counter_histogram(images.counters, request.counter) if counter_range else None,
            }
            self._publish(ViewFrame(image, request, level, scale, frame_timings, scene_serial))

    def _bounds(self, scene, scene_serial: int):
        """The scene's world bounds, read once a scene (every vertex: 79 ms at 4M triangles,
        before each pan or zoom of an orthographic view)."""
        if self._bounds_of is None or self._bounds_of[0] != scene_serial:
            self._bounds_of = (scene_serial, scene.world_bounds())
        return self._bounds_of[1]

    def _update_tree(self, scene, scene_serial, request, request_serial, refittable):
        """Build, refit or keep the tree; None when a newer scene (or Esc, or closing) cancelled it."""
        import bvhlab

        def progress(fraction: float) -> bool:
            with self._cv:
                if self._closed or self._paused or scene_serial != self._scene_serial:
                    return False
                self._status, self._redraw = f"Building BVH ({request.tree.config.method}) {fraction:.0%}", True
                return True

        try:
            tree = cache.tree(request.tree)
            return tree.update(scene, refittable, progress, threads=VIEWPORT_THREADS, policy=request.update)
        except bvhlab.BuildCancelled:
            return None

    def _settled(self, scene_serial: int, request_serial: int) -> bool:
        """Wait until the view has been still for SETTLE_S; False if it changed meanwhile."""
        with self._cv:
            while self._current(scene_serial, request_serial):
                still = time.monotonic() - self._request_time
                if still >= SETTLE_S:
                    return True
                self._cv.wait(SETTLE_S - still)
            return False

    def _publish(self, frame: ViewFrame) -> None:
        with self._cv:
            self._frame, self._redraw = frame, True
            timings = frame.timings
            self._status = f"{timings['level'].capitalize()} {timings['width']} × {timings['height']}" + (
                f", {timings['spp']} spp" if timings["spp"] > 1 else ""
            )
            if frame.request.note:
                self._status += f" | {frame.request.note}"
            if timings["overlay_note"]:
                self._status += f" | overlay: {timings['overlay_note']}"


def _levels(request: ViewRequest, ms_per_sample: float | None) -> list[tuple[str, float, int]]:
    """(level, scale, samples per pixel axis) to trace for a view, coarse to fine."""
    pixels = request.frustum.width * request.frustum.height
    if ms_per_sample is None:
        scale = 1 / 4
    else:
        scale = (request.budget_ms / max(ms_per_sample * pixels, 1e-9)) ** 0.5
    scale = min(max(scale, 1 / MAX_PREVIEW_DIVISOR), 1.0)
    levels = [] if scale > 0.7 else [("preview", scale, 1)]
    levels.append(("full", 1.0, 1))
    if request.settings.samples_per_axis > 1:
        levels.append(("refined", 1.0, request.settings.samples_per_axis))
    return levels


def close_all() -> None:
    for session in list(_sessions):
        session.close()


def busy_sessions() -> list[ViewportSession]:
    return [s for s in list(_sessions) if not s.closed and s.busy]
