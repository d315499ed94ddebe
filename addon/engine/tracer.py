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


class TraceCancelled(Exception):
    """`cancelled()` became true while a render ran; the samples finished before are kept."""


@dataclass(frozen=True)
class TraceImages:
    """Row 0 at the top. color: float32 (H, W, 4); depth: float32 (H, W) or None; heat: float32
    (H, W, 4) heat colours of the box tests per primary ray, or None; counters: float32 (H, W, 5)
    traversal counters per primary ray (bvhlab.counters.COUNTERS order), or None."""

    color: np.ndarray
    depth: np.ndarray | None
    heat: np.ndarray | None
    counters: np.ndarray | None = None


class TraceJob:
    """A render in sample passes (bvhlab.RenderJob): run to a number of samples per pixel, read the
    images of the samples so far at any time (after Esc too: what is finished is kept)."""

    def __init__(self, job, width: int, height: int, keeps_counters: bool = False):
        self._job = job
        self.size = (width, height)
        self.keeps_counters = keeps_counters  # started with traversal_counters

    @property
    def samples_per_pixel(self) -> int:
        return self._job.samples_per_pixel

    @property
    def samples_done(self) -> int:
        return self._job.samples_done

    def run(self, samples: int | None = None, cancelled=None) -> None:
        """Traces until every pixel has `samples` samples (default: all). With `cancelled`, raises
        TraceCancelled within one dispatch of it returning True."""
        import bvhlab

        try:
            self._job.run(samples, progress=None if cancelled is None else (lambda fraction: not cancelled()))
        except bvhlab.RenderCancelled:
            raise TraceCancelled() from None

    def images(self, depth: bool = False, heat: bool = False, counters: bool = False) -> TraceImages:
        result = self._job.result(color=True, depth=depth, cost=False, heat=heat, counters=counters)
        return TraceImages(result.color, result.depth, result.heat, result.counters)

    @property
    def timings(self) -> dict:
        return self._job.timings


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

    def check_size(self, width: int, height: int) -> None:
        """ValueError for an image this backend does not render, before anything is allocated."""
        self.renderer.check_size(width, height)

    def start(
        self, scene, bvh, camera, width: int, height: int, options, threads: int = 0, heat: bool = False
    ) -> TraceJob:
        """A render of `scene` seen from `camera` (a bvhlab.Camera or View) with `options` (a
        bvhlab.RenderOptions), nothing traced yet; `threads`: the CPU reference's (0: every core);
        `heat`: its images will include the heatmap pass (the cost kept; without it the CPU's wide
        walk traces camera rays ahead, eight at a time)."""
        job = self.renderer.start(
            scene, bvh, width, height, camera=camera, options=options, threads=threads, keep_cost=heat
        )
        return TraceJob(job, width, height, options.traversal_counters)

    def trace(self, scene, bvh, camera, width: int, height: int, options, threads: int = 0, cancelled=None):
        """(TraceImages, timings) of the whole render (the Combined image, and the counters where
        `options` keeps them). With `cancelled`, raises TraceCancelled within one dispatch of it
        returning True."""
        job = self.start(scene, bvh, camera, width, height, options, threads)
        job.run(cancelled=cancelled)
        return job.images(counters=options.traversal_counters), job.timings


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
