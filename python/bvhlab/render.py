"""`bvhlab.render`: the report's Whitted tracer with the BVH overlay pass, on Vulkan or the CPU.

Both backends run the same tracer code (shaders/tracer/*.glsl: GLSL that also compiles as C++),
so the CPU reference is the oracle for the GPU image and the fallback where Vulkan is missing.
A render is a job in sample passes (`Renderer.start`): a viewport can show a coarse image first and
refine it, a long render shows progress and stops on Ctrl-C or when its progress callable says so.
"""

from __future__ import annotations

import numbers
import threading
import time

from . import _checks, _core
from ._render_job import RenderCancelled, RenderJob, RenderResult  # noqa: F401  (this module's API)
from ._render_scene import SceneCache
from ._render_settings import View, render_settings
from .bvh import Bvh
from .instanced import InstancedBvh
from .overlay_levels import traced_cap_note
from .render_options import DEFAULT_HEIGHT, DEFAULT_WIDTH, RenderOptions, options_from
from .scene import Camera, Scene

BACKENDS = ("auto", "vulkan", "cpu")
TRAVERSALS: tuple[str, ...] = tuple(_core.TRAVERSALS)
#: The renderers' traversal where none is asked for (RenderSettings in C++): the stack walk, on pairs
#: of child boxes, nearer child first.
DEFAULT_TRAVERSAL: str = _core.DEFAULT_TRAVERSAL
MODES: tuple[str, ...] = tuple(_core.RENDER_MODES)
MAX_RAY_DEPTH: int = _core.MAX_RAY_DEPTH
MAX_SAMPLES_PER_AXIS: int = _core.MAX_SAMPLES_PER_AXIS
HAS_VULKAN = bool(getattr(_core, "HAS_VULKAN", False))
RenderIncomplete = _core.RenderIncomplete  # a pixel could not finish (RuntimeError)


class VulkanUnavailable(RuntimeError):
    """No Vulkan loader, driver or device (or bvhlab was built without Vulkan)."""


if HAS_VULKAN:
    VulkanUnavailable = _core.VulkanUnavailable  # type: ignore[misc]  # noqa: F811  (the C++ exception type itself)


def render(
    scene: Scene,
    bvh: Bvh | InstancedBvh,
    width: int = DEFAULT_WIDTH,
    height: int = DEFAULT_HEIGHT,
    *,
    backend: str = "auto",
    camera: Camera | View | None = None,
    options: RenderOptions | None = None,
    threads: int = 0,
    device: str | None = None,
    validation: bool | None = None,
    progress=None,
    **option_changes,
):
    """Render `scene` with its tree `bvh`; returns (image, timings). An instanced scene renders with
    its `InstancedBvh` (`bvhlab.build(scene)`): the tracers walk the TLAS and each mesh's tree, and
    the box overlay draws the TLAS's boxes.

    image: float32 (height, width, 4), row 0 at the top, linear RGB, alpha 1 (with film_transparent
    or a holdout: RenderResult.color's alpha, premultiplied).
    timings: upload_ms, overlay_ms, trace_ms, readback_ms, total_ms, dispatches, device (which
    device rendered), backend ("vulkan" or "cpu"), reason (why that backend), heatmap_scale (the
    box tests the heatmap shows red: its legend's top), traversal (the walk that rendered), and
    shadow_rays_opaque / shadow_rays_glass (the CPU's wide walk in a scene with a transparent
    material, or one hidden from shadow rays: shadow rays whose nearest crossing was opaque,
    answered by it, and glass or hidden, left to the stack walk; 0 elsewhere), camera_rays_ahead
    (the CPU's wide walk of a flat scene: camera rays traced ahead, eight at a time where they run
    together, as a render that returns no cost image traces them; 0 elsewhere), and overlay_note
    where the overlay of a two-level tree's BLAS boxes ("blas", "both") leaves boxes out (at most
    MAX_OVERLAY_BOXES are drawn: which instances' boxes are, in words; the key is absent when none
    is left out).

    backend: "auto" (a Vulkan GPU if there is one, else the CPU reference: on a CPU Vulkan
    driver such as lavapipe the CPU reference is several times faster), "vulkan" or "cpu".
    camera: a Camera or View; default: the scene's. options: a RenderOptions (samples, bounces,
    the box overlay, traversal, mode, ...; default RenderOptions()), with any of its fields given
    by name on top (`render(scene, bvh, samples_per_axis=2)`). progress: called with the fraction
    done; a false result stops the render (RenderCancelled). Ctrl-C stops it too
    (KeyboardInterrupt). device / validation: Vulkan device (index or name substring) and the
    Khronos validation layer.
    """
    return default_renderer(backend, device, validation).render(
        scene,
        bvh,
        width,
        height,
        camera=camera,
        options=options_from(options, option_changes),
        threads=threads,
        progress=progress,
    )


class Renderer:
    """A backend kept alive across frames: the Vulkan instance, device and pipelines are made once,
    and the scene is made (and uploaded) again only when the tree, its geometry or the materials
    change. Safe to share between threads (renders on one Vulkan device run one at a time)."""

    def __init__(
        self,
        backend: str = "auto",
        *,
        device: str | None = None,
        validation: bool | None = None,
        force_staging: bool = False,
        threads: int = 0,
    ):
        _checks.choice("backend", backend, BACKENDS)
        self.threads = _checks.integer("threads", threads, 0, 4096)
        device = _device(backend, device)
        validation = None if validation is None else _checks.flag("validation", validation)  # "no" read as True
        force_staging = _checks.flag("force_staging", force_staging)
        self._vulkan, self.backend, self.reason = _choose_backend(backend, device, validation, force_staging)
        self._validation, self._force_staging = validation, force_staging  # for like()
        self._cache = SceneCache()
        self._lock = threading.Lock()  # the cached scene, the upload and the job started on it go together
        self._uploaded = None

    def like(self) -> Renderer:
        """A new Renderer made as this one was (backend, device, validation, threads), with its own
        scene cache and upload: for frames of several trees taken in turn, each of which would
        otherwise make and upload its scene again at every frame (compare's rounds)."""
        # the backend and device this one resolved to, not "auto" again
        device = self._vulkan.device_name if self._vulkan is not None else None
        return Renderer(
            "vulkan" if device is not None else "cpu",
            device=device,
            validation=self._validation,
            force_staging=self._force_staging,
            threads=self.threads,
        )

    @property
    def fallback(self) -> str | None:
        """Why "auto" rendered on the CPU (None when it did not)."""
        return self.reason if self.backend == "cpu" and self.reason.startswith("auto") else None

    @property
    def device(self) -> str:
        return self._vulkan.device_name if self._vulkan else "CPU reference"

    @property
    def bresenham_lines(self) -> bool:
        """Whether the overlay's lines follow the CPU reference's rule, one pixel a column or row
        (the CPU reference: always; Vulkan: where the device has Bresenham lines)."""
        return bool(self._vulkan.bresenham_lines) if self._vulkan else True

    @property
    def max_line_width(self) -> float:
        """The widest overlay line this backend draws: `line_width` is clamped to it (the CPU
        reference: the settings' limit, 16; Vulkan: the device's, 1 without wide lines)."""
        return float(self._vulkan.max_line_width) if self._vulkan else float(_core.MAX_LINE_WIDTH)

    @property
    def max_image_dimension(self) -> int:
        """Pixels per side this backend renders at most (Vulkan: the device's limit)."""
        return int(self._vulkan.max_image_dimension) if self._vulkan else int(_core.MAX_IMAGE_DIMENSION)

    def check_size(self, width: int, height: int) -> None:
        """Raises ValueError for an image size this backend does not render (empty, or above
        max_image_dimension per side), TypeError for a size that is not two integers: for callers
        that must refuse a size before they allocate anything for it (as `start` does)."""
        width, height = _checks.integer("width", width, 1, 2**31), _checks.integer("height", height, 1, 2**31)
        _core.validate_image_size(width, height, self.max_image_dimension)

    def validation_messages(self) -> list[str]:
        """Validation-layer warnings and errors since the last call (Vulkan with validation on)."""
        return list(self._vulkan.take_validation_messages()) if self._vulkan else []

    @property
    def validation_errors(self) -> int:
        return self._vulkan.validation_error_count if self._vulkan else 0

    def start(
        self,
        scene: Scene,
        bvh: Bvh | InstancedBvh,
        width: int = DEFAULT_WIDTH,
        height: int = DEFAULT_HEIGHT,
        *,
        camera: Camera | View | None = None,
        options: RenderOptions | None = None,
        threads: int | None = None,
        keep_cost: bool = True,
        **option_changes,
    ) -> RenderJob:
        """A RenderJob (sample passes, nothing traced yet). `options` and its fields by name as for
        `bvhlab.render`. `threads`: CPU reference threads (default: the Renderer's, 0 = every core).
        `keep_cost`: keep each pixel's cost (box tests per primary ray: RenderJob.result's cost and
        heat); without it the CPU tracer's wide walk traces a flat scene's camera rays ahead, eight
        at a time where they run together (the same image, faster), and result(cost=True) or
        heat=True raise ValueError. The heatmap mode, whose image the cost is, keeps it."""
        threads = self.threads if threads is None else _checks.integer("threads", threads, 0, 4096)
        options = options_from(options, option_changes).for_backend(cpu=self._vulkan is None)
        settings = render_settings(scene, bvh, width, height, options, camera)
        settings.keep_cost = _checks.flag("keep_cost", keep_cost) or options.mode == "heatmap"
        start = time.perf_counter()
        # the backend "auto" renders the wide walk, which only the CPU tracer has, on the CPU
        wide_on_cpu = self._vulkan is not None and options.traversal == "wide" and self.reason.startswith("auto")
        # a thread inside a render's work (its progress callable) holds that render's locks, which a
        # thread holding this lock may be waiting for (it uploads to the Vulkan device or starts a
        # job there): asked once, not waited for (the CPU tracer's start waits for no such lock)
        waits = self._vulkan is None or not _core.inside_render_work()
        if not self._lock.acquire(blocking=waits):
            raise RuntimeError(
                "this renderer is starting a job on another thread, and this thread is inside a render's work "
                "(a call from its progress callable): call it after that work returns"
            )
        try:
            render_scene = self._cache.get(scene, bvh, options)
            prepare_ms = (time.perf_counter() - start) * 1e3
            upload_ms = 0.0
            if self._vulkan is None or wide_on_cpu:
                job = _core.start_cpu(render_scene, settings, threads)
            else:
                if self._uploaded is not render_scene:
                    # a failed upload leaves the device's scene empty (sky): no scene is on it then
                    self._uploaded = None
                    upload_ms = self._vulkan.upload(render_scene)
                    self._uploaded = render_scene
                job = self._vulkan.start(settings)
        finally:
            self._lock.release()
        timings = {
            "prepare_ms": prepare_ms,
            "upload_ms": upload_ms,
            "backend": "cpu" if wide_on_cpu else self.backend,
            "traversal": options.traversal,  # the walk that rendered ("auto" made one: for_backend)
            "reason": "auto: the wide traversal is the CPU tracer's" if wide_on_cpu else self.reason,
            "heatmap_scale": render_scene.heatmap_scale(settings),  # the heatmap's legend (bvhlab.legend)
        }
        if self.fallback or wide_on_cpu:
            timings["fallback"] = timings["reason"]
        overlay_note = traced_cap_note(bvh, options)  # the cap was said in the add-on's sidebar alone (an audit)
        if overlay_note:
            timings["overlay_note"] = overlay_note
        return RenderJob(job, settings, timings)

    def render(
        self,
        scene: Scene,
        bvh: Bvh | InstancedBvh,
        width: int = DEFAULT_WIDTH,
        height: int = DEFAULT_HEIGHT,
        *,
        progress=None,
        keep_cost: bool = False,
        **start_arguments,
    ):
        """The whole render at once: (image, timings), as `bvhlab.render`. The image alone is
        returned, so no cost is kept unless `keep_cost` (`start`'s: each camera ray then walks
        alone, as a render that keeps the cost walks it)."""
        job = self.start(scene, bvh, width, height, keep_cost=keep_cost, **start_arguments)
        job.run(progress=progress)
        result = job.result(depth=False, cost=False)
        return result.color, result.timings


def _device(backend: str, device) -> str | None:
    """The Vulkan device asked for: None, a name substring, or an index (an int, or its digits).
    TypeError for another type (an int was refused in nanobind's words); ValueError with the CPU
    backend, which has none (it was ignored)."""
    if device is None:
        return None
    if isinstance(device, numbers.Integral) and not isinstance(device, bool):
        device = str(_checks.integer("device", device, 0, 2**31 - 1))
    if not isinstance(device, str):
        raise TypeError(f"device must be a Vulkan device's index or a part of its name, got {type(device).__name__}")
    if backend == "cpu" and device:
        raise ValueError(f"device {device!r} names a Vulkan device, and the backend is 'cpu'")
    return device


def _choose_backend(backend: str, device, validation, force_staging):
    """(Vulkan renderer or None, "vulkan" or "cpu", why). Vulkan's settings asked of the CPU
    backend are refused, as `device` is (they were ignored: an audit)."""
    if backend == "cpu":
        for name, value in (("validation", validation), ("force_staging", force_staging)):
            if value:
                raise ValueError(f"{name}=True is a Vulkan setting, and the backend is 'cpu'")
        return None, "cpu", "requested"
    try:
        vulkan = _make_vulkan(device, validation, force_staging)
    except VulkanUnavailable as e:
        if backend == "vulkan":
            raise
        return None, "cpu", f"auto: Vulkan unavailable ({e}); rendered on the CPU reference"
    if backend == "auto" and not device and vulkan.device_type == "cpu":
        return (
            None,
            "cpu",
            (
                f"auto: the only Vulkan device is {vulkan.device_name}, a CPU driver; the CPU "
                f"reference traces several times faster there"
            ),
        )
    kind = vulkan.device_type
    return (
        vulkan,
        "vulkan",
        "requested" if backend == "vulkan" else f"auto: Vulkan device {vulkan.device_name} ({kind})",
    )


_default_renderers: dict = {}
_default_lock = threading.Lock()


def default_renderer(backend: str = "auto", device: str | None = None, validation: bool | None = None) -> Renderer:
    """The process-wide Renderer for these options (made on first use; shared by threads)."""
    key = (backend, device, validation)
    with _default_lock:
        if key not in _default_renderers:
            _default_renderers[key] = Renderer(backend, device=device, validation=validation)
        return _default_renderers[key]


def _make_vulkan(device, validation, force_staging):
    import os

    if not HAS_VULKAN:
        raise VulkanUnavailable(
            "this build of bvhlab has no Vulkan backend (glslc or the Vulkan headers were missing when it was compiled)"
        )
    if not _core.vulkan_loader_available():
        raise VulkanUnavailable(
            "no Vulkan loader (libvulkan.so.1): install libvulkan1 and a driver, "
            "e.g. apt-get install libvulkan1 mesa-vulkan-drivers"
        )
    if validation is None:
        validation = os.environ.get("BVHLAB_VULKAN_VALIDATION", "") not in ("", "0")
    return _core.VulkanRenderer(device or "", bool(validation), bool(force_staging))
