"""A render in sample passes (`RenderJob`, from `bvhlab.Renderer.start`) and what it produces
(`RenderResult`); re-exported by `bvhlab.render`."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import _checks, _core


class RenderCancelled(Exception):
    """The progress callable of a render said stop (returned a false value)."""


@dataclass(frozen=True)
class RenderResult:
    """What a render produces, row 0 at the top (None where not asked for).
    color: float32 (H, W, 4), linear RGB, alpha 1 (heat colours in mode "heatmap"); with
    film_transparent, alpha is the share of the pixel's camera rays that show something, and with
    a holdout material (on any film) the share that meet none, the colour premultiplied by it.
    depth: float32 (H, W), Blender's Z pass: the distance along the view axis of the nearest
    primary hit over the pixel's samples (where the overlay draws a line in front, the line's);
    1e10 where nothing was hit, as Cycles writes.
    cost: float32 (H, W), box tests per primary ray, averaged over the pixel's samples. Where the
    overlay draws a line in front of a surface, a render that measures the walks (mode "heatmap",
    traversal_counters) counts the whole walk; a shaded render without counters stops the primary
    ray at the line (report §3.3), and its cost there is that shorter walk's. None where the job
    keeps no cost (Renderer.start's keep_cost).
    heat: float32 (H, W, 4), `cost` in the heatmap's colours (what mode "heatmap" shows as colour).
    counters: float32 (H, W, 5), the traversal counters per primary ray in bvhlab.counters.COUNTERS
    order, averaged over the pixel's samples (renders with RenderOptions(traversal_counters=True)).
    samples: samples every pixel has (after a cancelled run some pixels have one more)."""

    color: np.ndarray | None
    depth: np.ndarray | None
    cost: np.ndarray | None
    samples: int
    timings: dict
    heat: np.ndarray | None = None
    counters: np.ndarray | None = None


class RenderJob:
    """A render in sample passes (from `Renderer.start`): `run` adds samples to every pixel,
    `result` gives the images of the samples so far. One call at a time per job; safe to use from
    any thread."""

    def __init__(self, core_job, settings, timings: dict):
        self._job, self._settings, self._timings = core_job, settings, timings

    @property
    def samples_per_pixel(self) -> int:
        return self._job.samples_per_pixel

    @property
    def samples_done(self) -> int:
        """Samples every pixel has."""
        return self._job.samples_done

    @property
    def done(self) -> bool:
        return self.samples_done >= self.samples_per_pixel

    def run(self, samples: int | None = None, progress=None) -> None:
        """Traces until every pixel has `samples` samples (default: all, samples_per_pixel).
        `progress` is called with the fraction of this run done; a false result stops it
        (RenderCancelled); so does Ctrl-C (KeyboardInterrupt). A stopped run keeps every sample
        completed so far, and run() may be called again. A run that has traced every sample it
        was asked for is not stopped by the answer to its last report (the CPU reference's 1.0: a
        finished image was raised as RenderCancelled "at 16 of 16 samples", where Vulkan, whose
        last report comes before its last round, finished: an audit)."""
        target = self.samples_per_pixel if samples is None else _checks.integer("samples", samples, 0, 1 << 16)
        if progress is not None and not callable(progress):
            raise TypeError(f"progress must be callable (fraction -> bool) or None, got {type(progress).__name__}")
        if not self._job.run(target, progress) and self.samples_done < target:
            raise RenderCancelled(
                f"render stopped by its progress callable at {self.samples_done} of {target} samples per pixel"
            )

    def result(
        self,
        color: bool = True,
        depth: bool = True,
        cost: bool | None = None,
        heat: bool = False,
        counters: bool = False,
    ) -> RenderResult:
        """The images of the samples so far (see RenderResult). `cost` and `heat` need a job that
        keeps the cost (Renderer.start's keep_cost; `cost` None: where it does), `counters` one
        started with traversal_counters=True (ValueError otherwise)."""
        color, depth = _checks.flag("color", color), _checks.flag("depth", depth)  # "no" read as True
        heat, counters = _checks.flag("heat", heat), _checks.flag("counters", counters)
        cost = bool(self._settings.keep_cost) if cost is None else _checks.flag("cost", cost)
        h, w = self._settings.height, self._settings.width
        images = (
            np.empty((h, w, 4), np.float32) if color else None,
            np.empty((h, w), np.float32) if depth else None,
            np.empty((h, w), np.float32) if cost else None,
        )
        heat_image = np.empty((h, w, 4), np.float32) if heat else None
        counter_image = np.empty((h, w, len(_core.TRAVERSAL_COUNTERS)), np.float32) if counters else None
        samples, timings = self._job.resolve(*images, heat_image, counter_image)  # of one moment
        return RenderResult(
            *images, samples=samples, timings={**timings, **self._timings}, heat=heat_image, counters=counter_image
        )

    @property
    def timings(self) -> dict:
        return {**self._job.timings, **self._timings}
