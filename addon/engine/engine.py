"""The render engine "bvhlab Whitted": the report's Whitted tracer and BVH overlay (report §3.2-3.3)
behind Blender's own render pipeline (F12, the command line, animation, passes, output formats)
and the 3D viewport's Rendered shading. The class only routes Blender's calls: final renders to
final.FinalRender, the viewport to viewport.ViewportSession (a worker thread) and display.FrameDisplay."""

from __future__ import annotations

import contextlib
import warnings
import weakref

import bpy

from .. import state
from . import passes
from .settings import fixed_light_distance

ENGINE_ID = "BVHLAB_WHITTED"
#: Each engine's viewport worker by the engine's id (closed by the engine's __del__).
_viewports: dict[int, object] = {}
#: How often (s) the UI thread looks for a new viewport frame to draw.
REDRAW_POLL_S = 0.05


class BVHLAB_RE_whitted(bpy.types.RenderEngine):
    bl_idname = ENGINE_ID
    bl_label = "bvhlab Whitted"
    bl_use_preview = False
    bl_use_shading_nodes_custom = False  # materials are Blender's shader nodes (Principled BSDF, ...)

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self._final = None
        self._viewport = None
        self._live = None
        self._light_fixed = False  # the viewport's LiveScene is lit by the scene's fixed light distance
        self._display = None

    def __del__(self):
        # by id, not self._viewport: an engine freed after Blender removed its RNA struct (a
        # traceback holding it) cannot read its own attributes, and its worker thread stayed
        viewport = _viewports.pop(id(self), None)
        if viewport is not None:
            viewport.close()

    # -- final renders ---------------------------------------------------------------------------
    def update(self, data=None, depsgraph=None):
        from .final import FinalRender

        if self._final is None:
            self._final = FinalRender()
        self._final.sync(self, depsgraph)

    def render(self, depsgraph):
        if self._final is not None:
            self._final.render(self, depsgraph)

    def update_render_passes(self, scene=None, renderlayer=None):
        if scene is not None and renderlayer is not None:
            passes.register(self, scene, renderlayer)

    # -- the viewport ----------------------------------------------------------------------------
    def view_update(self, context, depsgraph):
        from bvhlab.blender import ExportError, LiveScene

        from .viewport import ViewportSession

        if self._viewport is None:
            self._viewport, self._live = ViewportSession(), LiveScene("visible", require_camera=False, allow_empty=True)
            _viewports[id(self)] = self._viewport
            _watch_for_frames(self._viewport)
        fixed = fixed_light_distance(context.scene)
        if fixed is not None:
            self._live.light_distance, self._light_fixed = fixed, True
        elif self._light_fixed:  # back to measured: measured again at this sync
            self._live.light_distance, self._light_fixed = None, False
        try:
            with _quiet_export_warnings():
                report = self._live.sync(depsgraph, context.scene, context.view_layer)
        except ExportError as error:
            self._viewport.set_error(f"bvhlab: {error}")
            return
        except Exception as error:  # a bug: shown in the viewport, never raised into Blender's update
            from ..operator_support import describe_error

            self._viewport.set_error(f"bvhlab: {describe_error(error)}")
            return
        # an instanced scene is traced two-level, with the tree the sidebar and F12 use (issue 34)
        self._viewport.set_scene(self._live.scene, report)

    def view_draw(self, context, depsgraph):
        from .display import FrameDisplay
        from .view_request import view_request

        if self._viewport is None:
            return
        blender_scene = depsgraph.scene
        try:
            request = view_request(context, blender_scene)
        except Exception as error:  # a bug: said in the viewport's status, never raised into Blender's draw
            from ..operator_support import describe_error

            self.update_stats("", f"bvhlab: {describe_error(error)}")
            return
        self._viewport.request(request)
        frame = self._viewport.latest_frame()
        if frame is not None:
            if self._display is None:
                self._display = FrameDisplay()
            self._display.draw(frame)
            _record(blender_scene, frame, self._display)
        self.update_stats("", _status(self._viewport.status(), frame, self._display))


@contextlib.contextmanager
def _quiet_export_warnings():
    """The viewport substitutes a missing light or camera silently; other export warnings go to
    the console as usual."""
    from bvhlab.blender import SubstituteWarning

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", SubstituteWarning)
        yield


def _status(status: str, frame, display) -> str:
    """Cycles-style viewport status: what is happening, then the last frame's times and device."""
    if frame is None:
        return status
    t = frame.timings
    tree = f"BVH {t['tree']}" + (f" {t['build_ms']:.0f} ms" if t["tree"] != "kept" else "")
    return f"{status} | {tree} | trace {t['trace_ms']:.0f} ms | draw {display.draw_ms:.1f} ms | {t['device']}"


def _record(blender_scene, frame, display) -> None:
    record = dict(frame.timings, draw_ms=display.draw_ms, upload_ms=display.upload_ms)
    with state.lock:
        state.last_viewport.setdefault(state.key(blender_scene), {})[frame.level] = record


def _watch_for_frames(session) -> None:
    """A UI-thread timer that redraws the Rendered viewports when the session has a new frame or
    status. It holds the session weakly and stops with it."""
    ref = weakref.ref(session)

    def tick():
        current = ref()
        if current is None or current.closed:
            return None
        if current.take_redraw():
            tag_rendered_viewports()
        return REDRAW_POLL_S

    bpy.app.timers.register(tick, first_interval=REDRAW_POLL_S)


def tag_rendered_viewports() -> None:
    window_manager = bpy.context.window_manager
    for window in window_manager.windows if window_manager else ():
        for area in window.screen.areas:
            if area.type == "VIEW_3D" and area.spaces.active.shading.type == "RENDERED":
                area.tag_redraw()
