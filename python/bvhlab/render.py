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
from dataclasses import dataclass

import numpy as np

from . import _checks, _core
from ._render_scene import SceneCache
from .bvh import Bvh
from .scene import Camera, Scene

BACKENDS = ("auto", "vulkan", "cpu")
TRAVERSALS: tuple[str, ...] = tuple(_core.RENDER_TRAVERSALS)
MODES: tuple[str, ...] = tuple(_core.RENDER_MODES)
MAX_RAY_DEPTH: int = _core.MAX_RAY_DEPTH
MAX_SAMPLES_PER_AXIS: int = _core.MAX_SAMPLES_PER_AXIS
HAS_VULKAN = bool(getattr(_core, "HAS_VULKAN", False))
RenderIncomplete = _core.RenderIncomplete  # a pixel could not finish (RuntimeError)


class VulkanUnavailable(RuntimeError):
    """No Vulkan loader, driver or device (or bvhlab was built without Vulkan)."""


if HAS_VULKAN:
    VulkanUnavailable = _core.VulkanUnavailable  # type: ignore[misc]  # noqa: F811  (the C++ exception type itself)


class RenderCancelled(Exception):
    """The progress callable of a render said stop (returned a false value)."""


@dataclass(frozen=True)
class View:
    """A camera given directly, as Blender's camera or a viewport region gives it: position, view
    direction, up, vertical field of view in degrees, image-plane aspect (None: the image's),
    and lens shift in fractions of the image plane's larger side (Blender's shift_x, shift_y)."""

    position: tuple[float, float, float]
    forward: tuple[float, float, float]
    up: tuple[float, float, float] = (0.0, 0.0, 1.0)
    fov_y: float = 45.0
    aspect: float | None = None
    shift_x: float = 0.0
    shift_y: float = 0.0


@dataclass(frozen=True)
class RenderResult:
    """What a render produces, row 0 at the top (None where not asked for).
    color: float32 (H, W, 4), linear RGB, alpha 1 (heat colours in mode "heatmap").
    depth: float32 (H, W), Blender's Z pass: the distance along the view axis of the nearest
    primary hit over the pixel's samples (where the overlay draws a line in front, the line's);
    1e10 where nothing was hit, as Cycles writes.
    cost: float32 (H, W), box tests per primary ray, averaged over the pixel's samples.
    heat: float32 (H, W, 4), `cost` in the heatmap's colours (what mode "heatmap" shows as colour).
    samples: samples every pixel has (after a cancelled run some pixels have one more)."""

    color: np.ndarray | None
    depth: np.ndarray | None
    cost: np.ndarray | None
    samples: int
    timings: dict
    heat: np.ndarray | None = None


def render(
    scene: Scene,
    bvh: Bvh,
    width: int = 800,
    height: int = 600,
    *,
    backend: str = "auto",
    camera: Camera | View | None = None,
    samples_per_axis: int = 1,
    max_depth: int = 5,
    overlay_depth: tuple[int, int] | None = None,
    traversal: str = "stack",
    mode: str = "shade",
    color_by_depth: bool = True,
    line_width: float = 1.0,
    heatmap_scale: float | None = None,
    threads: int = 0,
    device: str | None = None,
    validation: bool | None = None,
    progress=None,
):
    """Render `scene` with its tree `bvh`; returns (image, timings).

    image: float32 (height, width, 4), row 0 at the top, linear RGB, alpha 1.
    timings: upload_ms, overlay_ms, trace_ms, readback_ms, total_ms, dispatches, device (which
    device rendered), backend ("vulkan" or "cpu") and reason (why that backend).

    backend: "auto" (a Vulkan GPU if there is one, else the CPU reference: on a CPU Vulkan
    driver such as lavapipe the CPU reference is several times faster), "vulkan" or "cpu".
    camera: a Camera or View; default: the scene's. samples_per_axis: n for n×n supersampling.
    max_depth: bounces of reflection and refraction (0..MAX_RAY_DEPTH). overlay_depth=(a, b):
    draw the boxes of tree depths a..b (report §3.3). traversal: "stack" or "stackless" (report
    §3.1). mode: "shade" or "heatmap" (box tests of the primary rays, blue = few, red =
    heatmap_scale or more; default 8 × tree height). progress: called with the fraction done;
    a false result stops the render (RenderCancelled). Ctrl-C stops it too (KeyboardInterrupt).
    device / validation: Vulkan device (index or name substring) and the Khronos validation layer.
    """
    return default_renderer(backend, device, validation).render(
        scene,
        bvh,
        width,
        height,
        camera=camera,
        samples_per_axis=samples_per_axis,
        max_depth=max_depth,
        overlay_depth=overlay_depth,
        traversal=traversal,
        mode=mode,
        color_by_depth=color_by_depth,
        line_width=line_width,
        heatmap_scale=heatmap_scale,
        threads=threads,
        progress=progress,
    )


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
        completed so far, and run() may be called again."""
        target = self.samples_per_pixel if samples is None else _checks.integer("samples", samples, 0, 1 << 16)
        if not self._job.run(target, progress):
            raise RenderCancelled(
                f"render stopped by its progress callable at {self.samples_done} of "
                f"{self.samples_per_pixel} samples per pixel"
            )

    def result(self, color: bool = True, depth: bool = True, cost: bool = True, heat: bool = False) -> RenderResult:
        """The images of the samples so far (see RenderResult)."""
        h, w = self._settings.height, self._settings.width
        images = (
            np.empty((h, w, 4), np.float32) if color else None,
            np.empty((h, w), np.float32) if depth else None,
            np.empty((h, w), np.float32) if cost else None,
        )
        heat_image = np.empty((h, w, 4), np.float32) if heat else None
        self._job.resolve(*images, heat_image)
        return RenderResult(*images, samples=self.samples_done, timings=self.timings, heat=heat_image)

    @property
    def timings(self) -> dict:
        return {**self._job.timings, **self._timings}


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
        self._vulkan, self.backend, self.reason = _choose_backend(backend, device, validation, force_staging)
        self._cache = SceneCache()
        self._lock = threading.Lock()  # the cached scene, the upload and the job started on it go together
        self._uploaded = None

    @property
    def fallback(self) -> str | None:
        """Why "auto" rendered on the CPU (None when it did not)."""
        return self.reason if self.backend == "cpu" and self.reason.startswith("auto") else None

    @property
    def device(self) -> str:
        return self._vulkan.device_name if self._vulkan else "CPU reference"

    def validation_messages(self) -> list[str]:
        """Validation-layer warnings and errors since the last call (Vulkan with validation on)."""
        return list(self._vulkan.take_validation_messages()) if self._vulkan else []

    @property
    def validation_errors(self) -> int:
        return self._vulkan.validation_error_count if self._vulkan else 0

    def start(
        self, scene: Scene, bvh: Bvh, width: int = 800, height: int = 600, *, threads: int | None = None, **options
    ) -> RenderJob:
        """A RenderJob (sample passes, nothing traced yet). Options as for `bvhlab.render`, and
        steps_per_dispatch (16..60000: how the work is cut, never the image; default: adaptive)
        and max_steps_per_pixel (a pixel needing more work in one run raises RenderIncomplete;
        default: the most a correct trace of the scene can take). `threads`: CPU reference
        threads (default: the Renderer's, 0 = every core)."""
        threads = self.threads if threads is None else _checks.integer("threads", threads, 0, 4096)
        settings = render_settings(scene, bvh, width, height, **options)
        start = time.perf_counter()
        with self._lock:
            render_scene = self._cache.get(scene, bvh)
            prepare_ms = (time.perf_counter() - start) * 1e3
            upload_ms = 0.0
            if self._vulkan is None:
                job = _core.start_cpu(render_scene, settings, threads)
            else:
                if self._uploaded is not render_scene:
                    upload_ms = self._vulkan.upload(render_scene)
                    self._uploaded = render_scene
                job = self._vulkan.start(settings)
        timings = {"prepare_ms": prepare_ms, "upload_ms": upload_ms, "backend": self.backend, "reason": self.reason}
        if self.fallback:
            timings["fallback"] = self.fallback
        return RenderJob(job, settings, timings)

    def render(self, scene: Scene, bvh: Bvh, width: int = 800, height: int = 600, *, progress=None, **options):
        """The whole render at once: (image, timings), as `bvhlab.render`."""
        job = self.start(scene, bvh, width, height, **options)
        job.run(progress=progress)
        result = job.result(depth=False, cost=False)
        return result.color, result.timings


def _choose_backend(backend: str, device, validation, force_staging):
    """(Vulkan renderer or None, "vulkan" or "cpu", why)."""
    if backend == "cpu":
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


def render_settings(
    scene: Scene,
    bvh: Bvh,
    width,
    height,
    *,
    camera=None,
    samples_per_axis=1,
    max_depth=5,
    overlay_depth=None,
    traversal="stack",
    mode="shade",
    color_by_depth=True,
    line_width=1.0,
    heatmap_scale=None,
    steps_per_dispatch=None,
    max_steps_per_pixel=None,
) -> _core.RenderSettings:
    """The typed settings of a render. Types are checked here; values once, in C++ (ValueError)."""
    if not isinstance(scene, Scene):
        raise TypeError(f"scene must be a bvhlab.Scene, got {type(scene).__name__}")
    if not isinstance(bvh, Bvh):
        raise TypeError(f"bvh must be a bvhlab.Bvh, got {type(bvh).__name__}")
    s = _core.RenderSettings()
    s.width, s.height = _checks.integer("width", width, 0, 2**31), _checks.integer("height", height, 0, 2**31)
    s.samples_per_axis = _checks.integer("samples_per_axis", samples_per_axis, 0, 2**31)
    s.max_ray_depth = _checks.integer("max_depth", max_depth, 0, 2**31)
    s.camera = _camera(scene, camera)
    _set_light(s, scene, camera)
    s.sky = scene.sky
    _set_overlay(s, overlay_depth)
    s.overlay_color_by_depth = bool(color_by_depth)
    s.line_width = _real("line_width", line_width)
    s.traversal = _core.parse_traversal(_name("traversal", traversal))
    s.mode = _core.parse_render_mode(_name("mode", mode))
    s.heatmap_scale = None if heatmap_scale is None else _real("heatmap_scale", heatmap_scale)
    if steps_per_dispatch is not None:
        s.steps_per_dispatch = _checks.integer("steps_per_dispatch", steps_per_dispatch, 0, 2**31)
    if max_steps_per_pixel is not None:
        s.max_steps_per_pixel = _checks.integer("max_steps_per_pixel", max_steps_per_pixel, 0, 2**63)
    s.validate()
    return s


def _name(what: str, value) -> str:
    if not isinstance(value, str):
        raise TypeError(f"{what} must be a string, got {type(value).__name__}")
    return value


def _triple(name: str, value) -> tuple[float, float, float]:
    try:
        v = tuple(_real(name, x) for x in value)
    except TypeError:
        raise TypeError(f"{name} must be three numbers, got {value!r}") from None
    if len(v) != 3:
        raise ValueError(f"{name} must be three numbers, got {len(v)}")
    return v


def _real(name: str, value) -> float:
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise TypeError(f"{name} must be a number, got {type(value).__name__}")
    return float(value)


def _camera(scene: Scene, camera) -> _core.Camera:
    c = _core.Camera()
    camera = scene.camera if camera is None else camera
    if camera is None:  # nothing to frame: bvhlab.defaults' fallback camera
        from .defaults import camera_placement

        position, target, up, fov = camera_placement(scene.bounds() if scene.primitive_count else None)
        camera = Camera(position, target, up, fov)
    if isinstance(camera, Camera):
        c.position, c.up, c.fov_y = camera.position, camera.up, camera.fov_y
        c.forward = tuple(np.subtract(camera.look_at, camera.position))
    elif isinstance(camera, View):
        c.position, c.forward = _triple("camera position", camera.position), _triple("camera forward", camera.forward)
        c.up = _triple("camera up", camera.up)
        c.fov_y = _real("camera fov_y", camera.fov_y)
        c.aspect = 0.0 if camera.aspect is None else _real("camera aspect", camera.aspect)
        c.shift_x, c.shift_y = _real("camera shift_x", camera.shift_x), _real("camera shift_y", camera.shift_y)
    else:
        raise TypeError(f"camera must be a bvhlab.Camera or bvhlab.View, got {type(camera).__name__}")
    return c


def _set_light(s, scene: Scene, camera) -> None:
    light = scene.light
    if light is None:
        from .scene import default_light

        look = s.camera
        light = default_light(Camera(tuple(look.position), tuple(np.add(look.position, look.forward)), tuple(look.up)))
    s.light.position, s.light.color, s.light.intensity = light.position, light.color, float(light.intensity)


def _set_overlay(s, overlay_depth) -> None:
    if overlay_depth is None:
        return
    if not isinstance(overlay_depth, (tuple, list)) or len(overlay_depth) != 2:
        raise TypeError(f"overlay_depth must be a pair (depth_min, depth_max) of tree depths, got {overlay_depth!r}")
    s.overlay = True
    s.overlay_depth_min = _checks.integer("overlay depth_min", overlay_depth[0], 0, 255)
    s.overlay_depth_max = _checks.integer("overlay depth_max", overlay_depth[1], 0, 255)


def save_png(image: np.ndarray, path) -> None:
    """Write a float RGBA (or RGB) image, row 0 at the top, as an 8-bit sRGB PNG."""
    from .png import write_png

    write_png(image, path)
