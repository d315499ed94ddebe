"""The parts of a `bvhlab.Scene` besides its geometry: Whitted materials, the camera and its lens, a
view (a camera without a light's defaults), the point light, the sky, and the defaults that frame
a scene's bounds."""

from __future__ import annotations

import enum
import math
import numbers
from dataclasses import dataclass

import numpy as np

from . import _checks, _core, defaults

#: Points (vertices, sphere extents, ray origins, the camera) lie within ±MAX_COORDINATE, where
#: bvhlab's float32 ray tests cannot overflow (core_cpp/include/bvhlab/coordinate_range.h says why).
MAX_COORDINATE = float(_core.MAX_COORDINATE)


def _vec3(name: str, value) -> tuple[float, float, float]:
    """Three finite numbers (numpy's too; not strings or bools: "abc" was a ValueError naming no
    field, ("0", "-5", "1") was taken: an audit)."""
    try:
        items = tuple(value) if not isinstance(value, (str, bytes)) else None
    except TypeError:
        items = None
    if items is None or not all(isinstance(x, numbers.Real) and not isinstance(x, bool) for x in items):
        raise TypeError(f"{name} must be three numbers, got {value!r}")
    if len(items) != 3:
        raise ValueError(f"{name} must be three numbers, got {len(items)}")
    v = (float(items[0]), float(items[1]), float(items[2]))
    if not all(math.isfinite(x) for x in v):
        raise ValueError(f"{name} must be finite, got {v}")
    return v


#: The largest colour, light intensity or light power (colour × intensity) a scene takes: the tracer
#: sums them in float32 (3.4e38), a few times over a pixel (a light colour of 3e38 gave infinite
#: pixels).
MAX_RADIANCE = 1e30


def _radiance(name: str, value) -> tuple[float, float, float]:
    """Three finite numbers in [0, MAX_RADIANCE] (a colour: a negative one darkened pixels below 0)."""
    v = _vec3(name, value)
    if not all(0.0 <= x <= MAX_RADIANCE for x in v):
        raise ValueError(f"{name} must be three numbers in [0, {MAX_RADIANCE:g}], got {v}")
    return v


def _in_range(name: str, point: tuple[float, float, float]) -> None:
    """ValueError where `point` lies outside the supported coordinate range (±MAX_COORDINATE)."""
    if max(abs(x) for x in point) > MAX_COORDINATE:
        raise ValueError(f"{name} {point} lies outside the supported coordinate range ±{MAX_COORDINATE:.5g} (2^40)")


def _row3(row: np.ndarray, first: int) -> tuple[float, float, float]:
    """Three numbers of a saved row, from `first`."""
    return float(row[first]), float(row[first + 1]), float(row[first + 2])


#: The tracer's rays (report §2.1), for Material.hidden_from: Rays.CAMERA, SHADOW, REFLECTION,
#: REFRACTION (Cycles' Object ▸ Visibility ▸ Ray Visibility: Camera, Shadow, Glossy, Transmission).
class Rays(enum.IntFlag):
    """The tracer's rays, as bits (Material.hidden_from); the core's values (gpu_types.h RAY_*)."""

    CAMERA = int(_core.RAY_BITS["CAMERA"])
    SHADOW = int(_core.RAY_BITS["SHADOW"])
    REFLECTION = int(_core.RAY_BITS["REFLECTION"])
    REFRACTION = int(_core.RAY_BITS["REFRACTION"])


@dataclass(frozen=True)
class Material:
    """Whitted material (report §2.1): a colour, a reflective and a transparent factor, an IOR; and
    `holdout` (Cycles' Holdout): a hole in the image where a camera ray meets it (no colour, alpha 0,
    the sky's depth, on an opaque film too), black to other rays; its shadow stays. `hidden_from`:
    the rays (Rays flags) that pass through it as if it were not there (Cycles' Ray Visibility:
    Rays.CAMERA | Rays.SHADOW, say, is seen only in reflections and refractions)."""

    color: tuple[float, float, float] = defaults.MATERIAL[:3]  # type: ignore[assignment]  # three, by the core
    reflective: float = defaults.MATERIAL[3]
    transparent: float = defaults.MATERIAL[4]
    ior: float = defaults.MATERIAL[5]
    holdout: bool = bool(defaults.MATERIAL[6])
    hidden_from: Rays = Rays(int(defaults.MATERIAL[7]))

    def __post_init__(self):
        object.__setattr__(self, "color", _radiance("material color", self.color))
        for name in ("reflective", "transparent"):
            x = float(getattr(self, name))
            if not 0.0 <= x <= 1.0:
                raise ValueError(f"material {name} must be in [0, 1], got {x}")
            object.__setattr__(self, name, x)
        # what is reflected and what is transmitted of the light arriving (report §2.1): more than
        # all of it made light (reflective 1 with transparent 1: pixels up to 1.8, 22.5 between two)
        if self.reflective + self.transparent > 1.0 + 1e-6:
            raise ValueError(
                f"material reflective + transparent must be at most 1, got {self.reflective} + {self.transparent}"
            )
        # finite in float32, the tracer's (1e300 was taken, then refused at render time as "NaN")
        if not (math.isfinite(self.ior) and 0 < self.ior <= float(np.finfo(np.float32).max)):
            raise ValueError(f"material ior must be a positive number within float32's range, got {self.ior}")
        object.__setattr__(self, "holdout", _checks.flag("material holdout", self.holdout))
        hidden = self.hidden_from
        if isinstance(hidden, (bool, np.bool_)) or not isinstance(hidden, (numbers.Integral, Rays)):
            raise TypeError(f"material hidden_from must be Rays flags, got {hidden!r}")
        if not 0 <= int(hidden) <= int(~Rays(0)):
            raise ValueError(f"material hidden_from must be Rays flags (0 to {int(~Rays(0))}), got {int(hidden)}")
        object.__setattr__(self, "hidden_from", Rays(int(hidden)))

    def as_row(self) -> list[float]:
        """The material as the core reads it (render_defaults.h kMaterialFloats)."""
        row = [*self.color, self.reflective, self.transparent, float(self.ior)]
        return [*row, float(self.holdout), float(int(self.hidden_from))]


def material_rows(materials) -> np.ndarray:
    """float32 (M, 8): the materials' rows as the core reads them (Material.as_row)."""
    return np.array([m.as_row() for m in materials], np.float32).reshape(-1, len(defaults.MATERIAL))


#: Camera projections (core_cpp/include/bvhlab/camera.h): "perspective", "orthographic",
#: "equirectangular", "fisheye" (equidistant), as Blender's camera data and Cycles define them.
PROJECTIONS: tuple[str, ...] = tuple(_core.PROJECTIONS)


def _real(name: str, value) -> float:
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise TypeError(f"{name} must be a number, got {type(value).__name__}")
    return float(value)


def _reals(name: str, value, n: int) -> tuple[float, ...]:
    try:
        v = tuple(_real(name, x) for x in value)
    except TypeError:
        raise TypeError(f"{name} must be {n} numbers, got {value!r}") from None
    if len(v) != n:
        raise ValueError(f"{name} must be {n} numbers, got {len(v)}")
    return v


@dataclass(frozen=True, kw_only=True)
class Lens:
    """How a camera's image maps onto rays, as Blender's camera data (and Cycles) define it; the
    keyword fields of Camera and View. Values are checked in C++ (camera.h), once, when made.

    projection: one of PROJECTIONS. ortho_scale: the orthographic view's larger side (world units).
    aspect: image-plane width / height (None: the frame's; Blender's pixel aspect sets it).
    shift_x, shift_y: lens shift in fractions of the image plane's larger side (Blender's shift with
    sensor fit Auto; panoramic: fractions of the frame's width and height).
    clip_start, clip_end: primary rays see only what lies between them, along the view axis
    (panoramic: from the camera). aperture_radius (world units; 0: none) and focus_distance: depth
    of field through a thin lens. fisheye_fov: degrees across the frame, up to 1800 (past 360 the
    angle from the axis keeps growing to the frame's edge, as in Blender). latitude, longitude:
    (min, max) degrees of the equirectangular frame (bottom, top; left, right): latitudes within
    ±90, longitudes wrap past ±180, and a range from its max to its min mirrors the frame.
    region: (x0, y0, x1, y1), the part of the frame the image shows, in fractions of the frame
    from its top-left corner (Blender's render border). mirrored: the image mirrored left to
    right (a Blender camera whose world matrix has a negative determinant, as Cycles renders it)."""

    projection: str = "perspective"
    ortho_scale: float | None = None
    aspect: float | None = None
    shift_x: float = 0.0
    shift_y: float = 0.0
    clip_start: float = 0.0
    clip_end: float = math.inf
    aperture_radius: float = 0.0
    focus_distance: float = 10.0
    fisheye_fov: float = 180.0
    latitude: tuple[float, float] = (-90.0, 90.0)
    longitude: tuple[float, float] = (-180.0, 180.0)
    region: tuple[float, float, float, float] = (0.0, 0.0, 1.0, 1.0)
    mirrored: bool = False

    def _check_lens(self) -> None:
        """Types here (TypeError), values by the C++ camera's own checks (ValueError)."""
        if not isinstance(self.projection, str):
            raise TypeError(f"camera projection must be a string, got {type(self.projection).__name__}")
        for name in ("shift_x", "shift_y", "clip_start", "clip_end", "aperture_radius", "focus_distance"):
            object.__setattr__(self, name, _real(f"camera {name}", getattr(self, name)))
        object.__setattr__(self, "fisheye_fov", _real("camera fisheye_fov", self.fisheye_fov))
        for name in ("ortho_scale", "aspect"):
            if getattr(self, name) is not None:
                # (one float32 would hold only as 0, "not given", is refused by setting: probe)
                value = _checks.setting(f"camera {name}", _real(f"camera {name}", getattr(self, name)))
                object.__setattr__(self, name, value)
        object.__setattr__(self, "latitude", _reals("camera latitude", self.latitude, 2))
        object.__setattr__(self, "longitude", _reals("camera longitude", self.longitude, 2))
        object.__setattr__(self, "region", _reals("camera region", self.region, 4))
        object.__setattr__(self, "mirrored", _checks.flag("camera mirrored", self.mirrored))

    def _set_lens(self, c) -> None:
        """Copies the lens into a _core.Camera."""
        c.projection = _core.parse_projection(self.projection)
        c.ortho_scale = self.ortho_scale or 0.0
        c.aspect = self.aspect or 0.0
        c.shift_x, c.shift_y = self.shift_x, self.shift_y
        c.clip_start, c.clip_end = self.clip_start, self.clip_end
        c.aperture_radius, c.focus_distance = self.aperture_radius, self.focus_distance
        c.fisheye_fov = self.fisheye_fov
        c.latitude_min, c.latitude_max = self.latitude
        c.longitude_min, c.longitude_max = self.longitude
        c.region = self.region
        c.mirrored = self.mirrored

    def lens_row(self) -> list[float]:
        """The lens as numbers, in LENS_ROW's order (the scene file's camera row after its first 10)."""
        return [
            float(PROJECTIONS.index(self.projection)),
            self.ortho_scale or 0.0,
            self.aspect or 0.0,
            self.shift_x,
            self.shift_y,
            self.clip_start,
            self.clip_end,
            self.aperture_radius,
            self.focus_distance,
            self.fisheye_fov,
            *self.latitude,
            *self.longitude,
            *self.region,
            float(self.mirrored),
        ]

    @staticmethod
    def lens_fields(row) -> dict:
        """The keyword fields of a lens_row (LENS_ROW numbers, or one fewer: written before
        `mirrored`)."""
        r = [float(x) for x in row]
        if len(r) not in (LENS_ROW, LENS_ROW - 1):
            raise ValueError(f"a lens row has {LENS_ROW} numbers, got {len(r)}")
        if len(r) > 18 and r[18] not in (0.0, 1.0):
            raise ValueError(f"a lens row's mirrored flag is 0 or 1, got {r[18]}")
        index = int(r[0])
        if not (r[0] == index and 0 <= index < len(PROJECTIONS)):
            raise ValueError(f"camera projection code {r[0]} is not one of 0..{len(PROJECTIONS) - 1}")
        return {
            "projection": PROJECTIONS[index],
            "ortho_scale": r[1] or None,
            "aspect": r[2] or None,
            "shift_x": r[3],
            "shift_y": r[4],
            "clip_start": r[5],
            "clip_end": r[6],
            "aperture_radius": r[7],
            "focus_distance": r[8],
            "fisheye_fov": r[9],
            "latitude": (r[10], r[11]),
            "longitude": (r[12], r[13]),
            "region": (r[14], r[15], r[16], r[17]),
            "mirrored": len(r) > 18 and r[18] == 1.0,
        }


#: Numbers of a Lens in a scene file's camera row (after position, look_at, up and fov_y).
LENS_ROW = 19


@dataclass(frozen=True)
class Camera(Lens):
    """A camera at `position` looking at `look_at`, `up` above the view axis; perspective with a
    vertical field of view of fov_y degrees unless its lens (the keyword fields, see Lens) says
    otherwise."""

    position: tuple[float, float, float]
    look_at: tuple[float, float, float]
    up: tuple[float, float, float] = (0.0, 0.0, 1.0)
    fov_y: float = 45.0

    def __post_init__(self):
        for name in ("position", "look_at", "up"):
            object.__setattr__(self, name, _vec3(f"camera {name}", getattr(self, name)))
        object.__setattr__(self, "fov_y", _real("camera fov_y", self.fov_y))
        self._check_lens()
        _in_range("camera position", self.position)
        # the tracer works in float32: the two points must differ there, not only in float64
        look_at, position = np.array(self.look_at, np.float32), np.array(self.position, np.float32)
        if not np.any(look_at != position):
            raise ValueError(
                f"camera position and look_at coincide (in float32, the tracer's precision): "
                f"{self.position}, {self.look_at}"
            )
        self.core().validate()

    def core(self):
        """The _core.Camera the renderers take."""
        c = _core.Camera()
        c.position, c.up, c.fov_y = self.position, self.up, self.fov_y
        c.forward = tuple(np.subtract(self.look_at, self.position))
        self._set_lens(c)
        return c

    def as_row(self) -> list[float]:
        return [*self.position, *self.look_at, *self.up, float(self.fov_y), *self.lens_row()]

    @classmethod
    def from_row(cls, row) -> Camera:
        """The camera of a scene file's row: 10 numbers (a pinhole) or 10 + LENS_ROW (one fewer in
        files written before `mirrored`)."""
        row = [float(x) for x in row]
        if len(row) not in (10, 10 + LENS_ROW, 9 + LENS_ROW):
            raise ValueError(f"a camera row has 10 or {10 + LENS_ROW} numbers, got {len(row)}")
        lens = Lens.lens_fields(row[10:]) if len(row) > 10 else {}
        return cls(_row3(row, 0), _row3(row, 3), _row3(row, 6), row[9], **lens)


@dataclass(frozen=True)
class View(Lens):
    """A camera given directly, as Blender's camera or a viewport region gives it: position, view
    direction, up, vertical field of view in degrees (perspective), and its lens (the keyword
    fields, see Lens). Checked when made, as Camera is."""

    position: tuple[float, float, float]
    forward: tuple[float, float, float]
    up: tuple[float, float, float] = (0.0, 0.0, 1.0)
    fov_y: float = 45.0

    def __post_init__(self):
        for name in ("position", "forward", "up"):
            object.__setattr__(self, name, _reals(f"camera {name}", getattr(self, name), 3))
        object.__setattr__(self, "fov_y", _real("camera fov_y", self.fov_y))
        self._check_lens()
        _in_range("camera position", self.position)  # as Camera's (a render named the default light's instead)
        self.core().validate()

    def core(self):
        """The _core.Camera the renderers take."""
        c = _core.Camera()
        c.position, c.forward, c.up, c.fov_y = self.position, self.forward, self.up, self.fov_y
        self._set_lens(c)
        return c


@dataclass(frozen=True)
class Light:
    """Point light (report §2.1)."""

    position: tuple[float, float, float]
    color: tuple[float, float, float] = (1.0, 1.0, 1.0)
    intensity: float = 1.0

    def __post_init__(self):
        object.__setattr__(self, "position", _vec3("light position", self.position))
        object.__setattr__(self, "color", _radiance("light color", self.color))
        intensity = _checks.real(
            "light intensity", self.intensity
        )  # "1" and True were taken, or a TypeError naming nothing
        if not 0 <= intensity <= MAX_RADIANCE:
            raise ValueError(f"light intensity must be a number in [0, {MAX_RADIANCE:g}], got {intensity}")
        object.__setattr__(self, "intensity", intensity)
        if max(self.color) * self.intensity > MAX_RADIANCE:
            raise ValueError(
                f"light color × intensity must be at most {MAX_RADIANCE:g}, got {self.color} × {self.intensity}"
            )
        _in_range("light position", self.position)

    def as_row(self) -> list[float]:
        return [*self.position, *self.color, float(self.intensity)]


DEFAULT_SKY = defaults.SKY


def default_camera(bounds) -> Camera:
    """The camera that frames `bounds` (bvhlab.defaults.camera_placement: 45° vertical field of
    view, looking at the centre from the front-upper diagonal)."""
    position, target, up, fov = defaults.camera_placement(bounds)
    return Camera(position, target, up, fov)


def default_light(camera: Camera | View) -> Light:
    """A point light a little above and to the right of the camera (defaults.light_position). A
    Camera places it by the point it looks at; a View gives a direction only, so its light is
    placed as for the point one unit along it, in double precision: made from position + forward,
    a View's forward ×100 moved the light 100× as far (the same view, another picture), and far
    from the origin (a unit forward at 1e8) the two points were one in float32 and a valid View
    was refused as a camera looking at itself (a render without a light: probe)."""
    if isinstance(camera, View):
        position, forward = np.asarray(camera.position, np.float64), np.asarray(camera.forward, np.float64)
        target = tuple(position + forward / np.linalg.norm(forward))
        return Light(defaults.light_position(camera.position, target, camera.up))
    return Light(defaults.light_position(camera.position, camera.look_at, camera.up))
