"""`RenderOptions`: how a render traces, besides the scene, its tree, the camera and the size. The
one typed object every renderer of bvhlab is asked for — `bvhlab.render`, `Renderer.start`, the
CLI, `compare`, and in Blender the sidebar's Render, F12 and the Rendered viewport, which all take
it from the scene's settings in one place (the add-on's `BVHLAB_PG_settings.render_options`).
Defaults are the C++ RenderSettings' (render_settings.h); values are checked once, by the core,
when the options are made."""

from __future__ import annotations

import dataclasses
import numbers
from dataclasses import dataclass, fields

from . import _checks, _core
from .overlay_levels import LEVELS
from .scene_parts import _radiance

#: The core's defaults, read while the module loads (deleted after: a nanobind object still alive
#: when the interpreter ends is reported as a leak, which Blender 4.3 and bpy printed at every exit).
_CORE = _core.RenderSettings()
#: The image size where none is given (RenderSettings in C++), and the limits the UI shows.
DEFAULT_WIDTH: int = int(_CORE.width)
DEFAULT_HEIGHT: int = int(_CORE.height)
MAX_LINE_WIDTH: float = float(_core.MAX_LINE_WIDTH)
#: The renderers' traversals: the walks of the core (`bvhlab.TRAVERSALS`) and "auto", the fastest
#: walk of the backend that renders where no count of the walk is shown (`RenderOptions.for_backend`).
AUTO_TRAVERSAL = "auto"
RENDER_TRAVERSALS: tuple[str, ...] = (AUTO_TRAVERSAL, *_core.TRAVERSALS)


def _rgb(value) -> tuple[float, float, float]:
    return tuple(float(c) for c in value)  # type: ignore[return-value]


@dataclass(frozen=True)
class RenderOptions:
    """`samples_per_axis`: n for n×n samples per pixel. `max_depth`: bounces of reflection and
    refraction (0..MAX_RAY_DEPTH). `overlay_depth=(a, b)`: draw the boxes of tree depths a..b
    (report §3.3), coloured by depth (`color_by_depth`) or in `line_color`, `line_width` pixels
    wide; of a two-level tree (an InstancedBvh), `overlay_level` says whose: "tlas" (over the
    instances), "blas" (each mesh's tree moved into the world by each instance; the depth range
    applies within a BLAS; at most overlay_levels.MAX_OVERLAY_BOXES) or "both". `traversal`:
    "stack" or "stackless" (report §3.1), or "wide" (the CPU tracer only: each ray through the
    8-wide tree of the CPU queries, the same image several times faster; its cost counts 8 box
    tests a wide node visited; no traversal counters). `mode`: "shade" or "heatmap" (box tests of the primary
    rays, blue = few, red = `heatmap_scale` or more; default 8 × tree height).
    `traversal_counters`: keep every traversal counter per pixel (RenderResult.counters;
    bvhlab.counters; 20 more bytes a pixel). `film_transparent` (Blender's Film ▸ Transparent): a
    pixel's alpha is the share of its samples whose camera ray shows a surface or the overlay's
    line, its colour premultiplied (those that show nothing add none), as Cycles writes it; rays
    after a bounce still see the sky; mode "shade" only (the heatmap stays opaque).
    `steps_per_dispatch` (how the work is cut, never the image; default adaptive) and
    `max_steps_per_pixel` (a pixel needing more work in one run raises RenderIncomplete; default:
    the most a correct trace of the scene can take)."""

    samples_per_axis: int = int(_CORE.samples_per_axis)
    max_depth: int = int(_CORE.max_ray_depth)
    overlay_depth: tuple[int, int] | None = None
    color_by_depth: bool = bool(_CORE.overlay_color_by_depth)
    line_color: tuple[float, float, float] = _rgb(_CORE.overlay_color)
    line_width: float = float(_CORE.line_width)
    overlay_level: str = "tlas"
    traversal: str = _core.DEFAULT_TRAVERSAL
    mode: str = _CORE.mode.name
    heatmap_scale: float | None = None
    traversal_counters: bool = bool(_CORE.traversal_counters)
    film_transparent: bool = bool(_CORE.film_transparent)
    steps_per_dispatch: int | None = None
    max_steps_per_pixel: int | None = None

    def __post_init__(self):
        _checks.choice("overlay_level", self.overlay_level, LEVELS)
        check = _core.RenderSettings()  # a whole render's settings, checked by the core now
        self.apply(check)
        check.validate()

    @property
    def samples(self) -> int:
        """Samples per pixel."""
        return self.samples_per_axis**2

    def for_backend(self, cpu: bool, counts_shown: bool = False) -> RenderOptions:
        """These options with traversal "auto" made the walk it stands for on a backend (`cpu`: the
        CPU tracer renders; else Vulkan): the wide walk on the CPU where no count of the walk is
        shown (mode "shade", no traversal counters, and not `counts_shown`, e.g. a heatmap pass
        beside the image), else the stack walk, whose counts are the binary tree's box tests
        (report §3.1) and which is the faster walk on a GPU (results.md, "On a GPU"). The same
        image either way; another traversal is kept as it is."""
        if self.traversal != AUTO_TRAVERSAL:
            return self
        counted = counts_shown or self.mode == "heatmap" or self.traversal_counters
        return dataclasses.replace(self, traversal="wide" if cpu and not counted else _core.DEFAULT_TRAVERSAL)

    def replace(self, **changes) -> RenderOptions:
        """A copy with some options changed (unknown names: TypeError naming them)."""
        names = [f.name for f in fields(self)]
        unknown = sorted(set(changes) - set(names))
        if unknown:
            raise TypeError(f"unknown render option(s) {', '.join(unknown)}; expected: {', '.join(names)}")
        return dataclasses.replace(self, **changes)

    def apply(self, s: _core.RenderSettings) -> None:
        """Write these options into the core's RenderSettings (types checked here; values by its
        validate)."""
        s.samples_per_axis = _checks.integer(
            "samples_per_axis", self.samples_per_axis, 1, int(_core.MAX_SAMPLES_PER_AXIS)
        )
        s.max_ray_depth = _checks.integer("max_depth", self.max_depth, 0, int(_core.MAX_RAY_DEPTH))
        _set_overlay(s, self.overlay_depth)
        s.overlay_color_by_depth = _checks.flag("color_by_depth", self.color_by_depth)
        s.overlay_color = _triple("line_color", self.line_color)
        s.line_width = _real("line_width", self.line_width)
        s.traversal = _core.parse_traversal(_traversal(self.traversal))
        s.mode = _core.parse_render_mode(_name("mode", self.mode))
        # a number beyond float32's range is refused as given, not as the inf it would become
        s.heatmap_scale = None if self.heatmap_scale is None else _checks.setting("heatmap_scale", self.heatmap_scale)
        s.traversal_counters = _checks.flag("traversal_counters", self.traversal_counters)
        s.film_transparent = _checks.flag("film_transparent", self.film_transparent)
        if self.steps_per_dispatch is not None:
            s.steps_per_dispatch = _checks.integer("steps_per_dispatch", self.steps_per_dispatch, 0, 2**31)
        if self.max_steps_per_pixel is not None:
            s.max_steps_per_pixel = _checks.integer("max_steps_per_pixel", self.max_steps_per_pixel, 0, 2**63)


def options_from(options: RenderOptions | None, changes: dict) -> RenderOptions:
    """`options` (default: RenderOptions()) with `changes` by name on top: what the renderers' many
    keyword arguments become."""
    if options is None:
        options = RenderOptions()
    elif not isinstance(options, RenderOptions):
        raise TypeError(f"options must be a bvhlab.RenderOptions, got {type(options).__name__}")
    return options.replace(**changes) if changes else options


def _traversal(value) -> str:
    """The core's name of a traversal: "auto" where no backend made it one (`for_backend`) is the
    core's default walk, which every backend has."""
    name = _checks.choice("traversal", value, RENDER_TRAVERSALS)
    return _core.DEFAULT_TRAVERSAL if name == AUTO_TRAVERSAL else name


def _name(what: str, value) -> str:
    if not isinstance(value, str):
        raise TypeError(f"{what} must be a string, got {type(value).__name__}")
    return value


def _real(name: str, value) -> float:
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise TypeError(f"{name} must be a number, got {type(value).__name__}")
    return float(value)


def _triple(name: str, value) -> tuple[float, float, float]:
    try:
        v = tuple(_real(name, x) for x in value)
    except TypeError:
        raise TypeError(f"{name} must be three numbers, got {value!r}") from None
    # three, and a colour as a material's: a negative one drew pixels below 0, 3e38 infinite ones where
    # samples were summed (a helper's audit); NaN is bad input too
    return _radiance(name, v)


def _set_overlay(s, overlay_depth) -> None:
    if overlay_depth is None:
        return
    if not isinstance(overlay_depth, (tuple, list)) or len(overlay_depth) != 2:
        raise TypeError(f"overlay_depth must be a pair (depth_min, depth_max) of tree depths, got {overlay_depth!r}")
    s.overlay = True
    s.overlay_depth_min = _checks.integer("overlay depth_min", overlay_depth[0], 0, 255)
    s.overlay_depth_max = _checks.integer("overlay depth_max", overlay_depth[1], 0, 255)


del _CORE
