"""`bvhlab.Scene`: geometry, materials, camera, light and sky as numpy arrays, saved as `.npz`."""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from . import _checks, defaults

FORMAT_VERSION = 1


def _vec3(name: str, value) -> tuple[float, float, float]:
    try:
        v = tuple(float(x) for x in value)
    except TypeError:
        raise TypeError(f"{name} must be three numbers, got {value!r}") from None
    if len(v) != 3:
        raise ValueError(f"{name} must be three numbers, got {len(v)}")
    if not all(math.isfinite(x) for x in v):
        raise ValueError(f"{name} must be finite, got {v}")
    return v


@dataclass(frozen=True)
class Material:
    """Whitted material (report §2.1): a colour, a reflective and a transparent factor, an IOR."""
    color: tuple[float, float, float] = defaults.MATERIAL[:3]
    reflective: float = defaults.MATERIAL[3]
    transparent: float = defaults.MATERIAL[4]
    ior: float = defaults.MATERIAL[5]

    def __post_init__(self):
        object.__setattr__(self, "color", _vec3("material color", self.color))
        for name in ("reflective", "transparent"):
            x = float(getattr(self, name))
            if not 0.0 <= x <= 1.0:
                raise ValueError(f"material {name} must be in [0, 1], got {x}")
            object.__setattr__(self, name, x)
        if not (math.isfinite(self.ior) and self.ior > 0):
            raise ValueError(f"material ior must be a positive number, got {self.ior}")

    def as_row(self) -> list[float]:
        return [*self.color, self.reflective, self.transparent, float(self.ior)]


@dataclass(frozen=True)
class Camera:
    """Pinhole camera: position, the point it looks at, up vector, vertical field of view (degrees)."""
    position: tuple[float, float, float]
    look_at: tuple[float, float, float]
    up: tuple[float, float, float] = (0.0, 0.0, 1.0)
    fov_y: float = 45.0

    def __post_init__(self):
        for name in ("position", "look_at", "up"):
            object.__setattr__(self, name, _vec3(f"camera {name}", getattr(self, name)))
        if not (0.0 < float(self.fov_y) < 180.0):
            raise ValueError(f"camera fov_y must be in (0, 180) degrees, got {self.fov_y}")
        forward = np.subtract(self.look_at, self.position)
        if np.linalg.norm(forward) == 0:
            raise ValueError("camera position and look_at coincide")
        if np.linalg.norm(np.cross(forward, self.up)) == 0:
            raise ValueError("camera up is parallel to the viewing direction")

    def as_row(self) -> list[float]:
        return [*self.position, *self.look_at, *self.up, float(self.fov_y)]


@dataclass(frozen=True)
class Light:
    """Point light (report §2.1)."""
    position: tuple[float, float, float]
    color: tuple[float, float, float] = (1.0, 1.0, 1.0)
    intensity: float = 1.0

    def __post_init__(self):
        object.__setattr__(self, "position", _vec3("light position", self.position))
        object.__setattr__(self, "color", _vec3("light color", self.color))
        if not (math.isfinite(self.intensity) and self.intensity >= 0):
            raise ValueError(f"light intensity must be a non-negative number, got {self.intensity}")

    def as_row(self) -> list[float]:
        return [*self.position, *self.color, float(self.intensity)]


DEFAULT_SKY = defaults.SKY


@dataclass
class Scene:
    """What bvhlab builds and renders. Missing parts get defaults that make a two-line script work:
    a camera framing the bounds (45° vertical, from the front-upper diagonal, Z up), a point light
    near it, matte white materials and a soft blue sky."""
    triangles: np.ndarray = field(default_factory=lambda: np.zeros((0, 3, 3), np.float32))
    spheres: np.ndarray = field(default_factory=lambda: np.zeros((0, 4), np.float32))
    materials: list[Material] = field(default_factory=lambda: [Material()])
    tri_material: np.ndarray | None = None
    sphere_material: np.ndarray | None = None
    camera: Camera | None = None
    light: Light | None = None
    sky: tuple[float, float, float] = DEFAULT_SKY

    def __post_init__(self):
        self.triangles = _checks.float32_array("triangles", self.triangles, (3, 3))
        self.spheres = _checks.float32_array("spheres", self.spheres, (4,))
        if not self.materials:
            self.materials = [Material()]
        self.materials = [m if isinstance(m, Material) else Material(*m) for m in self.materials]
        self.tri_material = self._material_index("tri_material", self.tri_material, len(self.triangles))
        self.sphere_material = self._material_index("sphere_material", self.sphere_material, len(self.spheres))
        self.sky = _vec3("sky", self.sky)
        if self.camera is None and self.primitive_count:
            self.camera = default_camera(self.bounds())
        if self.light is None and self.camera is not None:
            self.light = default_light(self.camera)

    def _material_index(self, name: str, value, n: int) -> np.ndarray:
        if value is None:
            return np.zeros(n, np.int32)
        value = np.asarray(value)
        if n == 0 and value.size == 0:
            return np.zeros(0, np.int32)
        if value.shape != (n,) or not np.issubdtype(value.dtype, np.integer):
            raise ValueError(f"{name} must be {n} integers, got shape {value.shape} dtype {value.dtype}")
        if n and (value.min() < 0 or value.max() >= len(self.materials)):
            raise ValueError(f"{name} refers to a material that does not exist (have {len(self.materials)})")
        return value.astype(np.int32)

    @property
    def primitive_count(self) -> int:
        return len(self.triangles) + len(self.spheres)

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """(lo, hi) of all primitives; raises ValueError for an empty scene."""
        if not self.primitive_count:
            raise ValueError("the scene has no geometry")
        parts_lo, parts_hi = [], []
        if len(self.triangles):
            points = self.triangles.reshape(-1, 3)
            # one column at a time: numpy reduces contiguous columns several times faster
            parts_lo.append(np.array([points[:, k].min() for k in range(3)]))
            parts_hi.append(np.array([points[:, k].max() for k in range(3)]))
        if len(self.spheres):
            parts_lo.append((self.spheres[:, :3] - self.spheres[:, 3:]).min(0))
            parts_hi.append((self.spheres[:, :3] + self.spheres[:, 3:]).max(0))
        return np.min(parts_lo, 0), np.max(parts_hi, 0)

    def material_table(self) -> np.ndarray:
        """float32 (M, 6): r, g, b, reflective, transparent, ior."""
        return np.array([m.as_row() for m in self.materials], np.float32).reshape(-1, 6)

    # -- files ---------------------------------------------------------------------------------
    def save(self, path) -> None:
        """Write an `.npz` (no pickled objects) that `Scene.load` and the CLI read."""
        arrays = {
            "format_version": np.array(FORMAT_VERSION),
            "triangles": self.triangles, "spheres": self.spheres,
            "materials": np.array([m.as_row() for m in self.materials], np.float64).reshape(-1, 6),
            "tri_material": self.tri_material, "sphere_material": self.sphere_material,
            "sky": np.array(self.sky, np.float64),
        }
        if self.camera is not None:
            arrays["camera"] = np.array(self.camera.as_row(), np.float64)
        if self.light is not None:
            arrays["light"] = np.array(self.light.as_row(), np.float64)
        np.savez_compressed(Path(path), **arrays)

    @classmethod
    def load(cls, path) -> "Scene":
        path = Path(path)
        if not path.exists():
            raise FileNotFoundError(f"no scene file at {path}")
        with np.load(path, allow_pickle=False) as f:
            version = int(f["format_version"]) if "format_version" in f else None
            if version != FORMAT_VERSION:
                raise ValueError(f"{path} is not a bvhlab scene of format {FORMAT_VERSION} (found {version})")
            cam = f["camera"] if "camera" in f else None
            light = f["light"] if "light" in f else None
            return cls(
                triangles=np.ascontiguousarray(f["triangles"], np.float32),
                spheres=np.ascontiguousarray(f["spheres"], np.float32),
                materials=[Material(tuple(r[:3]), r[3], r[4], r[5]) for r in f["materials"]],
                tri_material=f["tri_material"], sphere_material=f["sphere_material"],
                camera=Camera(cam[0:3], cam[3:6], cam[6:9], cam[9]) if cam is not None else None,
                light=Light(light[0:3], light[3:6], light[6]) if light is not None else None,
                sky=tuple(f["sky"]),
            )


def default_camera(bounds) -> Camera:
    """The camera that frames `bounds` (bvhlab.defaults.camera_placement: 45° vertical field of
    view, looking at the centre from the front-upper diagonal)."""
    position, target, up, fov = defaults.camera_placement(bounds)
    return Camera(position, target, up, fov)


def default_light(camera: Camera) -> Light:
    """A point light a little above and to the right of the camera."""
    return Light(defaults.light_position(camera.position, camera.look_at, camera.up))
