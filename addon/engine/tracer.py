"""The render engine's one door to bvhlab's tracer: every call the engine makes into
`bvhlab.Renderer`, `Renderer.render` and `Bvh.intersect` is in this file, so moving to the tracer's
pass API (bounded work per dispatch, passes that accumulate and cancel, the camera given directly,
depth and heatmap outputs in the same render) changes this file only.

Today's API and what this adapter does about it:
- A Renderer takes its camera from the Scene: `trace` renders a shallow copy of the scene with the
  view's camera (the arrays are shared, so the renderer's upload cache still hits).
- `backend="auto"` still picks a CPU Vulkan driver (lavapipe, ~9× slower than the CPU reference
  on this kind of machine): `open_tracer` takes the CPU reference instead and says why.
- A render cannot be stopped once started: `trace(..., cancelled=)` runs it on a helper thread and
  returns as soon as `cancelled()` says so (TraceCancelled); the abandoned render finishes on its
  own and its image is dropped. One render at a time per Tracer (a lock).
- Depth is not a tracer output: `depth` intersects the primary rays through the pixel centres
  with `Bvh.intersect` (the rays of `shaders/tracer/shade.glsl`'s camera_ray_dir).
- The heatmap is a second render with mode="heatmap".
"""
from __future__ import annotations

import copy
import math
import threading
from dataclasses import dataclass, replace

import numpy as np

#: What Blender's render pipeline fills a Depth pass with before an engine writes it (its value
#: for "nothing here"); misses get it too.
MISS_DEPTH = 10e10
#: Vulkan device types on which the CPU reference is the faster tracer.
CPU_DEVICE_TYPES = ("cpu",)


class TraceCancelled(Exception):
    """`cancelled()` became true while a render ran; its result is dropped."""


@dataclass(frozen=True)
class TraceSettings:
    """One render's options, in the tracer's terms. `overlay`: (depth_min, depth_max) or None."""
    spp: int = 1
    max_depth: int = 5
    overlay: tuple | None = None
    color_by_depth: bool = True
    line_width: float = 1.0
    traversal: str = "stackless"
    mode: str = "shade"
    threads: int = 0  # CPU reference threads; 0 = every core

    def heatmap(self) -> "TraceSettings":
        return replace(self, mode="heatmap")

    def options(self) -> dict:
        return {"spp": self.spp, "max_depth": self.max_depth, "overlay_depth": self.overlay,
                "color_by_depth": self.color_by_depth, "line_width": self.line_width,
                "traversal": self.traversal, "mode": self.mode, "threads": self.threads}


class Tracer:
    """One backend, shared by final renders and viewports (renders run one at a time)."""

    def __init__(self, requested: str):
        import bvhlab

        self.requested = requested
        renderer = bvhlab.Renderer(requested)
        self.note = renderer.fallback
        if requested == "auto" and renderer.backend == "vulkan" and _device_type(renderer) in CPU_DEVICE_TYPES:
            self.note = (f"{renderer.device} is a CPU Vulkan driver; auto uses the CPU reference, which traces "
                         f"faster there")
            renderer = bvhlab.Renderer("cpu")
        self.renderer = renderer
        self._lock = threading.Lock()

    @property
    def device(self) -> str:
        """The device that renders, in words."""
        return self.renderer.device

    @property
    def backend(self) -> str:
        return self.renderer.backend

    def trace(self, scene, bvh, camera, width: int, height: int, settings: TraceSettings, cancelled=None):
        """(image float32 (height, width, 4) row 0 at the top, timings) of `scene` seen from `camera`
        (a bvhlab.Camera). With `cancelled`, raises TraceCancelled as soon as it returns True."""
        view = copy.copy(scene)  # shallow: same arrays, so the renderer's scene cache still hits
        view.camera = camera

        def render():
            with self._lock:
                return self.renderer.render(view, bvh, width, height, **settings.options())

        return render() if cancelled is None else _run_cancellable(render, cancelled)


_tracers: dict[str, Tracer] = {}
_tracers_lock = threading.Lock()


def open_tracer(backend: str) -> Tracer:
    """The process-wide Tracer for a backend choice ("auto", "vulkan", "cpu"), made on first use.
    Raises bvhlab.VulkanUnavailable for "vulkan" without a driver."""
    with _tracers_lock:
        if backend not in _tracers:
            _tracers[backend] = Tracer(backend)
        return _tracers[backend]


def forget_tracers() -> None:
    with _tracers_lock:
        _tracers.clear()


def _device_type(renderer) -> str:
    vulkan = getattr(renderer, "_vulkan", None)  # bridging until the tracer's auto does this itself
    return getattr(vulkan, "device_type", "") if vulkan is not None else ""


def _run_cancellable(work, cancelled, poll_s: float = 0.05):
    outcome: dict = {}

    def run():
        try:
            outcome["value"] = work()
        except BaseException as error:  # handed to the waiting thread, never lost in this one
            outcome["error"] = error

    thread = threading.Thread(target=run, name="bvhlab trace", daemon=True)
    thread.start()
    while thread.is_alive():
        if cancelled():
            raise TraceCancelled()
        thread.join(poll_s)
    if "error" in outcome:
        raise outcome["error"]
    return outcome["value"]


# -- depth ------------------------------------------------------------------------------------
def camera_basis(camera) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """forward, right, up (unit, float64) of a bvhlab.Camera, as the tracer makes them
    (core_cpp/src/render/render_scene.cpp make_frame_params)."""
    position, look_at, up = (np.asarray(v, np.float64) for v in (camera.position, camera.look_at, camera.up))
    forward = (look_at - position) / np.linalg.norm(look_at - position)
    right = np.cross(forward, up)
    right /= np.linalg.norm(right)
    return forward, right, np.cross(right, forward)


def primary_directions(camera, width: int, height: int) -> np.ndarray:
    """float32 (height·width, 3), row 0 at the top: the direction through each pixel centre,
    scaled so its component along the view axis is 1 (t along it is then the camera-space depth)."""
    forward, right, up = camera_basis(camera)
    tan_half = math.tan(math.radians(camera.fov_y) / 2)
    x = (2 * (np.arange(width) + 0.5) / width - 1) * tan_half * width / height
    y = (1 - 2 * (np.arange(height) + 0.5) / height) * tan_half
    dirs = forward + x[None, :, None] * right + y[:, None, None] * up
    return np.ascontiguousarray(dirs.reshape(-1, 3), np.float32)


def depth(bvh, camera, width: int, height: int) -> np.ndarray:
    """Blender's Depth (Z) pass, float32 (height, width), row 0 at the top: the distance along the
    view axis from the camera to the surface seen through each pixel centre (one sample per pixel,
    as Blender's Z pass), MISS_DEPTH where the ray hits nothing."""
    directions = primary_directions(camera, width, height)
    origins = np.ascontiguousarray(np.broadcast_to(np.asarray(camera.position, np.float32), directions.shape))
    t = bvh.intersect(origins, directions)["t"]
    return np.where(np.isfinite(t), t, MISS_DEPTH).astype(np.float32).reshape(height, width)
