"""The render engine's one door to bvhlab's tracer: every call the engine makes into
`bvhlab.Renderer` is in this file.

A render is a job in sample passes (`Renderer.start`): it is traced in bounded dispatches, the
camera is given directly, and the Combined image, Blender's Depth (the view-axis distance of the
nearest primary hit, 1e10 where nothing was hit, as Cycles writes) and the traversal-cost heatmap
come out of the same render. `cancelled()` is polled between dispatches, so Esc and a moved view
stop a render within one dispatch (TraceCancelled). `backend="auto"` picks the CPU reference
itself where the only Vulkan device is a CPU driver (lavapipe), and says why.
"""

from __future__ import annotations

import threading
from dataclasses import dataclass

import numpy as np

from bvhlab.render import DEFAULT_TRAVERSAL


class TraceCancelled(Exception):
    """`cancelled()` became true while a render ran; its result is dropped."""


@dataclass(frozen=True)
class TraceSettings:
    """One render's options, in the tracer's terms. `overlay`: (depth_min, depth_max) or None."""

    samples_per_axis: int = 1  # n of the n×n supersampling
    max_depth: int = 5
    overlay: tuple | None = None
    color_by_depth: bool = True
    line_width: float = 1.0
    traversal: str = DEFAULT_TRAVERSAL
    mode: str = "shade"
    threads: int = 0  # CPU reference threads; 0 = every core

    @property
    def samples(self) -> int:
        """Samples per pixel."""
        return self.samples_per_axis**2

    def options(self) -> dict:
        return {
            "samples_per_axis": self.samples_per_axis,
            "max_depth": self.max_depth,
            "overlay_depth": self.overlay,
            "color_by_depth": self.color_by_depth,
            "line_width": self.line_width,
            "traversal": self.traversal,
            "mode": self.mode,
        }


@dataclass(frozen=True)
class TraceImages:
    """Row 0 at the top. color: float32 (H, W, 4); depth: float32 (H, W) or None; heat: float32
    (H, W, 4) heat colours of the box tests per primary ray, or None."""

    color: np.ndarray
    depth: np.ndarray | None
    heat: np.ndarray | None


class Tracer:
    """One backend, shared by final renders and viewports (the Renderer is thread-safe)."""

    def __init__(self, requested: str):
        import bvhlab

        self.requested = requested
        self.renderer = bvhlab.Renderer(requested)
        self.note = self.renderer.fallback

    @property
    def device(self) -> str:
        """The device that renders, in words."""
        return self.renderer.device

    @property
    def backend(self) -> str:
        return self.renderer.backend

    def trace(
        self,
        scene,
        bvh,
        camera,
        width: int,
        height: int,
        settings: TraceSettings,
        cancelled=None,
        depth: bool = False,
        heat: bool = False,
    ):
        """(TraceImages, timings) of `scene` seen from `camera` (a bvhlab.Camera or View). With
        `cancelled`, raises TraceCancelled within one dispatch of it returning True."""
        import bvhlab

        job = self.renderer.start(
            scene, bvh, width, height, camera=camera, threads=settings.threads, **settings.options()
        )
        try:
            job.run(progress=None if cancelled is None else (lambda fraction: not cancelled()))
        except bvhlab.RenderCancelled:
            raise TraceCancelled() from None
        result = job.result(color=True, depth=depth, cost=False, heat=heat)
        return TraceImages(result.color, result.depth, result.heat), result.timings


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
