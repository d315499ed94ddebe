"""`bvhlab.render`: the report's Whitted tracer with the BVH overlay pass, on Vulkan or the CPU.

Both backends run the same tracer code (shaders/tracer/*.glsl: GLSL that also compiles as C++),
so the CPU reference is the oracle for the GPU image and the fallback where Vulkan is missing.
"""
from __future__ import annotations

import math
import os
import time

import numpy as np

from . import _checks, _core
from .bvh import Bvh
from .scene import DEFAULT_SKY, Camera, Light, Scene, default_camera, default_light

BACKENDS = ("vulkan", "cpu", "auto")
MODES = ("shade", "heatmap")
HAS_VULKAN = bool(getattr(_core, "HAS_VULKAN", False))
MAX_DEPTH = 15


class VulkanUnavailable(RuntimeError):
    """No Vulkan loader, driver or device (or bvhlab was built without Vulkan)."""


if HAS_VULKAN:
    VulkanUnavailable = _core.VulkanUnavailable  # noqa: F811  (the C++ exception type itself)


def render(scene: Scene, bvh: Bvh, width: int = 800, height: int = 600, *, backend: str = "vulkan",
           spp: int = 1, max_depth: int = 5, overlay_depth: tuple[int, int] | None = None,
           traversal: str = "stack", mode: str = "shade", color_by_depth: bool = True,
           line_width: float = 1.0, heatmap_scale: float | None = None, threads: int = 0,
           device: str | None = None, validation: bool | None = None):
    """Render `scene` with its tree `bvh`; returns (image, timings).

    image: float32 (height, width, 4), row 0 at the top, linear RGB, alpha 1.
    timings: upload_ms, overlay_ms, trace_ms, readback_ms, total_ms, device, backend (and
    "fallback" when backend="auto" had to use the CPU).

    spp: samples per pixel, a square number (n×n supersampling). max_depth: bounces of reflection
    and refraction (0..15). overlay_depth=(a, b): draw the boxes of tree depths a..b (report §3.3).
    traversal: "stack" or "stackless" (report §3.1). mode: "shade" or "heatmap" (box tests of the
    primary rays, blue = few, red = heatmap_scale or more; default 8 × tree height).
    device / validation: Vulkan device (index or name substring) and the Khronos validation layer.
    """
    return default_renderer(backend, device, validation).render(
        scene, bvh, width, height, spp=spp, max_depth=max_depth, overlay_depth=overlay_depth,
        traversal=traversal, mode=mode, color_by_depth=color_by_depth, line_width=line_width,
        heatmap_scale=heatmap_scale, threads=threads)


class Renderer:
    """A backend kept alive across frames: the Vulkan instance, device and pipelines are made once,
    and the scene is uploaded again only when the scene or the tree changes."""

    def __init__(self, backend: str = "vulkan", *, device: str | None = None, validation: bool | None = None,
                 force_staging: bool = False):
        _checks.choice("backend", backend, BACKENDS)
        self.backend, self.fallback = backend, None
        self._vulkan = None
        if backend in ("vulkan", "auto"):
            try:
                self._vulkan = _make_vulkan(device, validation, force_staging)
                self.backend = "vulkan"
            except VulkanUnavailable as e:
                if backend == "vulkan":
                    raise
                self.backend, self.fallback = "cpu", f"Vulkan unavailable ({e}); rendered on the CPU reference"
        self._uploaded = None  # the RenderScene on the device

    @property
    def device(self) -> str:
        return self._vulkan.device_name if self._vulkan else "CPU reference"

    def validation_messages(self) -> list[str]:
        """Validation-layer warnings and errors since the last call (Vulkan with validation on)."""
        return list(self._vulkan.take_validation_messages()) if self._vulkan else []

    @property
    def validation_errors(self) -> int:
        return self._vulkan.validation_error_count if self._vulkan else 0

    def render(self, scene: Scene, bvh: Bvh, width: int = 800, height: int = 600, **options):
        settings, threads = _settings(scene, bvh, width, height, **options)
        start = time.perf_counter()
        render_scene = _render_scene(scene, bvh)
        image = np.empty((settings["height"], settings["width"], 4), np.float32)
        prepare_ms = (time.perf_counter() - start) * 1e3
        if self._vulkan is None:
            timings = dict(_core.render_cpu(render_scene, settings, image, threads))
        else:
            upload_ms = 0.0
            if self._uploaded is not render_scene:
                upload_ms = self._vulkan.upload(render_scene)
                self._uploaded = render_scene
            timings = dict(self._vulkan.render(settings, image))
            timings["upload_ms"] = upload_ms
        timings["prepare_ms"] = prepare_ms
        timings["backend"] = self.backend
        if self.fallback:
            timings["fallback"] = self.fallback
        return image, timings


_default_renderers: dict = {}


def default_renderer(backend: str = "vulkan", device: str | None = None, validation: bool | None = None) -> Renderer:
    """The process-wide Renderer for these options (made on first use)."""
    key = (backend, device, validation)
    if key not in _default_renderers:
        _default_renderers[key] = Renderer(backend, device=device, validation=validation)
    return _default_renderers[key]


def _make_vulkan(device, validation, force_staging):
    if not HAS_VULKAN:
        raise VulkanUnavailable("this build of bvhlab has no Vulkan backend (glslc or the Vulkan headers "
                                "were missing when it was compiled)")
    if not _core.vulkan_loader_available():
        raise VulkanUnavailable("no Vulkan loader (libvulkan.so.1): install libvulkan1 and a driver, "
                                "e.g. apt-get install libvulkan1 mesa-vulkan-drivers")
    if validation is None:
        validation = os.environ.get("BVHLAB_VULKAN_VALIDATION", "") not in ("", "0")
    return _core.VulkanRenderer(device or "", bool(validation), bool(force_staging))


def _settings(scene: Scene, bvh: Bvh, width, height, *, spp=1, max_depth=5, overlay_depth=None,
              traversal="stack", mode="shade", color_by_depth=True, line_width=1.0, heatmap_scale=None,
              threads=0) -> tuple[dict, int]:
    if not isinstance(scene, Scene):
        raise TypeError(f"scene must be a bvhlab.Scene, got {type(scene).__name__}")
    if not isinstance(bvh, Bvh):
        raise TypeError(f"bvh must be a bvhlab.Bvh, got {type(bvh).__name__}")
    width = _checks.integer("width", width, 1, 1 << 20)
    height = _checks.integer("height", height, 1, 1 << 20)
    spp = _checks.integer("spp", spp, 1, 256)
    n = math.isqrt(spp)
    if n * n != spp:
        raise ValueError(f"spp must be a square number (n×n supersampling: 1, 4, 9, 16, ...), got {spp}")
    camera = scene.camera or (default_camera(scene.bounds()) if scene.primitive_count else
                              Camera((0.0, -5.0, 2.0), (0.0, 0.0, 0.0)))
    light = scene.light or default_light(camera)
    overlay = overlay_depth is not None
    lo, hi = 0, 0
    if overlay:
        if len(overlay_depth) != 2:
            raise ValueError(f"overlay_depth must be (depth_min, depth_max), got {overlay_depth!r}")
        lo = _checks.integer("overlay depth_min", overlay_depth[0], 0, 255)
        hi = _checks.integer("overlay depth_max", overlay_depth[1], 0, 255)
        if lo > hi:
            raise ValueError(f"overlay_depth ({lo}, {hi}): depth_min is greater than depth_max")
    settings = {
        "width": width, "height": height, "samples_per_axis": n,
        "max_depth": _checks.integer("max_depth", max_depth, 0, MAX_DEPTH),
        "camera_position": camera.position, "camera_look_at": camera.look_at, "camera_up": camera.up,
        "camera_fov_y": float(camera.fov_y),
        "light_position": light.position, "light_color": light.color, "light_intensity": float(light.intensity),
        "sky": tuple(scene.sky) if scene.sky is not None else DEFAULT_SKY,
        "overlay": overlay, "overlay_depth_min": lo, "overlay_depth_max": hi,
        "overlay_color_by_depth": bool(color_by_depth), "line_width": float(line_width),
        "traversal": {"stack": 0, "stackless": 1}[_checks.choice("traversal", traversal, ("stack", "stackless"))],
        "mode": {"shade": 0, "heatmap": 1}[_checks.choice("mode", mode, MODES)],
        "heatmap_scale": float(heatmap_scale or 0.0),
    }
    return settings, _checks.integer("threads", threads, 0, 4096)


def _render_scene(scene: Scene, bvh: Bvh):
    """The scene in GPU layout, cached on the tree for as long as the scene's arrays are the same."""
    key = (bvh.revision, id(scene.triangles), id(scene.spheres), id(scene.tri_material), id(scene.sphere_material),
           tuple(scene.materials))  # frozen dataclasses: compared by value
    cached = getattr(bvh, "_render_cache", None)
    if cached is not None and cached[0] == key:
        return cached[1]
    rs = _core.RenderScene(bvh._core, scene.triangles, scene.spheres, scene.material_table(),
                           scene.tri_material, scene.sphere_material)
    bvh._render_cache = (key, rs)
    return rs


def save_png(image: np.ndarray, path) -> None:
    """Write a float RGBA (or RGB) image, row 0 at the top, as an 8-bit sRGB PNG."""
    from .png import write_png

    write_png(image, path)
