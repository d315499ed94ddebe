"""`bvhlab.Scene`: geometry, materials, camera, light and sky as numpy arrays, saved as `.npz`."""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from . import _checks, _core, defaults
from ._npz import MAX_EXPANSION, Member, SceneFileError, read_npz, write_npz

#: Written by Scene.save; 2 added meshes and instances (issue 34). Files of every version listed in
#: READ_FORMAT_VERSIONS load.
FORMAT_VERSION = 2
READ_FORMAT_VERSIONS = (1, 2)
#: Points (vertices, sphere extents, ray origins, the camera) lie within ±MAX_COORDINATE, where
#: bvhlab's float32 ray tests cannot overflow (core_cpp/include/bvhlab/coordinate_range.h says why).
MAX_COORDINATE = float(_core.MAX_COORDINATE)


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


def _row3(row: np.ndarray, first: int) -> tuple[float, float, float]:
    """Three numbers of a saved row, from `first`."""
    return float(row[first]), float(row[first + 1]), float(row[first + 2])


@dataclass(frozen=True)
class Material:
    """Whitted material (report §2.1): a colour, a reflective and a transparent factor, an IOR."""

    color: tuple[float, float, float] = defaults.MATERIAL[:3]  # type: ignore[assignment]  # three, by the core
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
    of field through a thin lens. fisheye_fov: degrees across the frame. latitude, longitude:
    (min, max) degrees of the equirectangular frame (bottom, top; left, right).
    region: (x0, y0, x1, y1), the part of the frame the image shows, in fractions of the frame
    from its top-left corner (Blender's render border)."""

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

    def _check_lens(self) -> None:
        """Types here (TypeError), values by the C++ camera's own checks (ValueError)."""
        if not isinstance(self.projection, str):
            raise TypeError(f"camera projection must be a string, got {type(self.projection).__name__}")
        for name in ("shift_x", "shift_y", "clip_start", "clip_end", "aperture_radius", "focus_distance"):
            object.__setattr__(self, name, _real(f"camera {name}", getattr(self, name)))
        object.__setattr__(self, "fisheye_fov", _real("camera fisheye_fov", self.fisheye_fov))
        for name in ("ortho_scale", "aspect"):
            if getattr(self, name) is not None:
                object.__setattr__(self, name, _real(f"camera {name}", getattr(self, name)))
        object.__setattr__(self, "latitude", _reals("camera latitude", self.latitude, 2))
        object.__setattr__(self, "longitude", _reals("camera longitude", self.longitude, 2))
        object.__setattr__(self, "region", _reals("camera region", self.region, 4))

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
        ]

    @staticmethod
    def lens_fields(row) -> dict:
        """The keyword fields of a lens_row."""
        r = [float(x) for x in row]
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
        }


#: Numbers of a Lens in a scene file's camera row (after position, look_at, up and fov_y).
LENS_ROW = 18


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
        if max(abs(x) for x in self.position) > MAX_COORDINATE:
            raise ValueError(
                f"camera position {self.position} lies outside the supported coordinate range "
                f"±{MAX_COORDINATE:.5g} (2^40)"
            )
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
        """The camera of a scene file's row: 10 numbers (a pinhole) or 10 + LENS_ROW."""
        row = [float(x) for x in row]
        if len(row) not in (10, 10 + LENS_ROW):
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
    # None in the constructor means material 0 for all; the field always holds an int32 array.
    tri_material: np.ndarray = None  # type: ignore[assignment]
    sphere_material: np.ndarray = None  # type: ignore[assignment]
    camera: Camera | None = None
    light: Light | None = None
    sky: tuple[float, float, float] = DEFAULT_SKY
    # Instancing (issue 34; bvhlab.instanced). The scene's own triangles and spheres are mesh 0;
    # `meshes` adds meshes 1, 2, ... (float32 (T,3,3) triangle arrays); `mesh_tri_material`, when
    # given, holds the material index of each of their triangles (one int32 array per mesh; empty:
    # material 0 for all, as before; the Blender exporter fills it). Instance i places
    # mesh instance_mesh[i] by instance_transforms[i] (float32 (3,4), object to world, row-major).
    # Without instances every mesh is placed once where it was modelled: Scene(triangles=...) is
    # one mesh and one identity instance, the flat scene of before.
    meshes: list[np.ndarray] = field(default_factory=list)
    mesh_tri_material: list[np.ndarray] = field(default_factory=list)
    instance_mesh: np.ndarray | None = None
    instance_transforms: np.ndarray | None = None

    def __setattr__(self, name, value):
        # Every field is checked when it is set, in the constructor and after it, so a scene never
        # holds a float64 array, a NaN vertex or a camera that is a tuple (the error names the field).
        check = _FIELD_CHECKS.get(name)
        object.__setattr__(self, name, check(self, value) if check else value)

    def __post_init__(self):
        if self.camera is None and (self.primitive_count or any(len(m) for m in self.meshes)):
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
        """Primitives of the scene's own geometry (mesh 0)."""
        return len(self.triangles) + len(self.spheres)

    # -- instancing ----------------------------------------------------------------------------
    @property
    def is_instanced(self) -> bool:
        """True when the scene has meshes besides its own or instances given: bvhlab.build then
        makes a two-level tree (bvhlab.InstancedBvh)."""
        return bool(self.meshes) or self.instance_mesh is not None or self.instance_transforms is not None

    @property
    def mesh_count(self) -> int:
        return 1 + len(self.meshes)

    def mesh_triangles(self, k: int) -> np.ndarray:
        """The triangles of mesh k (0: the scene's own)."""
        return self.triangles if k == 0 else self.meshes[k - 1]

    def mesh_triangle_material(self, k: int) -> np.ndarray:
        """The material index of each triangle of mesh k: the scene's own (mesh 0) keep
        tri_material, the other meshes theirs in mesh_tri_material (material 0 when it is empty).
        Raises ValueError when mesh_tri_material does not match the meshes or the materials."""
        if k == 0:
            return self.tri_material
        triangles = self.meshes[k - 1]
        if not self.mesh_tri_material:
            return np.zeros(len(triangles), np.int32)
        if len(self.mesh_tri_material) != len(self.meshes):
            raise ValueError(
                f"mesh_tri_material has {len(self.mesh_tri_material)} arrays for {len(self.meshes)} meshes"
            )
        return self._material_index(f"mesh_tri_material of mesh {k}", self.mesh_tri_material[k - 1], len(triangles))

    def instances(self) -> tuple[np.ndarray, np.ndarray]:
        """(mesh index int32 (N,), object-to-world float32 (N,3,4)): the instances given, checked
        against each other and the meshes (ValueError naming the instance), or every mesh once
        where it was modelled."""
        if self.instance_mesh is None and self.instance_transforms is None:
            n = self.mesh_count
            return np.arange(n, dtype=np.int32), np.ascontiguousarray(np.tile(_IDENTITY, (n, 1, 1)))
        if self.instance_mesh is None or self.instance_transforms is None:
            raise ValueError("instance_mesh and instance_transforms are given together (one each per instance)")
        mesh, transforms = self.instance_mesh, self.instance_transforms
        if len(mesh) != len(transforms):
            raise ValueError(f"{len(mesh)} instance meshes but {len(transforms)} instance transforms")
        bad = np.flatnonzero((mesh < 0) | (mesh >= self.mesh_count))
        if len(bad):
            raise ValueError(
                f"instance {bad[0]} refers to mesh {mesh[bad[0]]}, but the scene has {self.mesh_count} "
                f"mesh{'es' if self.mesh_count != 1 else ''}"
            )
        return mesh, transforms

    def flattened(self) -> Scene:
        """The same geometry as one flat mesh: every instance's triangles moved into the world (the
        flat scene that a two-level tree must agree with). Spheres of mesh 0 move with its
        instances, which must then keep them spheres (rotation, uniform scale, translation)."""
        if not self.is_instanced:
            return self
        mesh_of, transforms = self.instances()
        tris, tri_mat, spheres, sphere_mat = [], [], [], []
        for k, t in zip(mesh_of, transforms.astype(np.float64)):
            src = self.mesh_triangles(int(k)).astype(np.float64)
            tris.append((src @ t[:, :3].T + t[:, 3]).astype(np.float32))
            tri_mat.append(self.mesh_triangle_material(int(k)))
            if k == 0 and len(self.spheres):
                spheres.append(_moved_spheres(self.spheres, t))
                sphere_mat.append(self.sphere_material)
        return Scene(
            triangles=np.ascontiguousarray(np.concatenate(tris or [np.zeros((0, 3, 3), np.float32)])),
            spheres=np.ascontiguousarray(np.concatenate(spheres or [np.zeros((0, 4), np.float32)])),
            materials=list(self.materials),
            tri_material=np.concatenate(tri_mat or [np.zeros(0, np.int32)]),
            sphere_material=np.concatenate(sphere_mat or [np.zeros(0, np.int32)]),
            camera=self.camera,
            light=self.light,
            sky=self.sky,
        )

    def _mesh_bounds(self, k: int) -> tuple[np.ndarray, np.ndarray] | None:
        parts_lo, parts_hi = [], []
        tris = self.mesh_triangles(k)
        if len(tris):
            points = tris.reshape(-1, 3)
            # one column at a time: numpy reduces contiguous columns several times faster
            parts_lo.append(np.array([points[:, c].min() for c in range(3)]))
            parts_hi.append(np.array([points[:, c].max() for c in range(3)]))
        if k == 0 and len(self.spheres):
            parts_lo.append((self.spheres[:, :3] - self.spheres[:, 3:]).min(0))
            parts_hi.append((self.spheres[:, :3] + self.spheres[:, 3:]).max(0))
        if not parts_lo:
            return None
        return np.min(parts_lo, 0), np.max(parts_hi, 0)

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """(lo, hi) of all primitives (of every instance, in the world); raises ValueError for an
        empty scene."""
        if self.is_instanced:
            return self._instanced_bounds()
        box = self._mesh_bounds(0)
        if box is None:
            raise ValueError("the scene has no geometry")
        return box

    def _instanced_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        mesh_of, transforms = self.instances()
        boxes = [self._mesh_bounds(k) for k in range(self.mesh_count)]
        corners_lo, corners_hi = [], []
        for k, t in zip(mesh_of, transforms.astype(np.float64)):
            box = boxes[int(k)]
            if box is None:
                continue
            corners = np.array([[box[(c >> a) & 1][a] for a in range(3)] for c in range(8)])
            world = corners @ t[:, :3].T + t[:, 3]
            corners_lo.append(world.min(0))
            corners_hi.append(world.max(0))
        if not corners_lo:
            raise ValueError("the scene has no geometry")
        return np.min(corners_lo, 0), np.max(corners_hi, 0)

    def material_table(self) -> np.ndarray:
        """float32 (M, 6): r, g, b, reflective, transparent, ior."""
        return np.array([m.as_row() for m in self.materials], np.float32).reshape(-1, 6)

    # -- files ---------------------------------------------------------------------------------
    def save(self, path) -> Path:
        """Write an `.npz` (no pickled objects) that `Scene.load` and the CLI read, exactly at `path`,
        which must end in .npz (never renamed); an existing file is replaced only once the new one
        is complete. Returns the path."""
        path = _checks.output_file(path, (".npz",), "scene file")
        arrays: dict[str, np.ndarray] = {
            "format_version": np.array(FORMAT_VERSION),
            "triangles": self.triangles,
            "spheres": self.spheres,
            "materials": np.array([m.as_row() for m in self.materials], np.float64).reshape(-1, 6),
            "tri_material": self.tri_material,
            "sphere_material": self.sphere_material,
            "sky": np.array(self.sky, np.float64),
        }
        if self.meshes:
            arrays["mesh_triangles"] = np.concatenate(self.meshes)
            arrays["mesh_triangle_counts"] = np.array([len(m) for m in self.meshes], np.int64)
            if self.mesh_tri_material:
                materials = [self.mesh_triangle_material(k) for k in range(1, self.mesh_count)]
                arrays["mesh_tri_material"] = np.concatenate(materials)
        if self.instance_mesh is not None or self.instance_transforms is not None:
            arrays["instance_mesh"], arrays["instance_transforms"] = self.instances()
        if self.camera is not None:
            arrays["camera"] = np.array(self.camera.as_row(), np.float64)
        if self.light is not None:
            arrays["light"] = np.array(self.light.as_row(), np.float64)
        return write_npz(path, arrays)

    @classmethod
    def load(cls, path, *, max_expansion: float = MAX_EXPANSION) -> Scene:
        """Read a scene written by `save`. Headers are checked before data is read: dtypes, shapes,
        counts that agree, and no more than `max_expansion` times the file's size once over 64 MiB
        (a small crafted file cannot claim gigabytes). Raises FileNotFoundError, or SceneFileError
        (a ValueError) naming the file and the problem."""
        path = Path(path)
        if not path.exists():
            raise FileNotFoundError(f"no scene file at {path}")
        f = read_npz(
            path,
            _FILE_MEMBERS,
            optional=("camera", "light", *_INSTANCING_MEMBERS),
            max_expansion=max_expansion,
            same_length=(("triangles", "tri_material"), ("spheres", "sphere_material")),
        )
        if int(f["format_version"]) not in READ_FORMAT_VERSIONS:
            raise SceneFileError(
                f"{path} is a bvhlab scene of format {int(f['format_version'])}; "
                f"this version reads formats {', '.join(map(str, READ_FORMAT_VERSIONS))}"
            )
        try:
            cam, light = f.get("camera"), f.get("light")
            return cls(
                triangles=np.ascontiguousarray(f["triangles"], np.float32),
                spheres=np.ascontiguousarray(f["spheres"], np.float32),
                materials=[Material(tuple(r[:3]), r[3], r[4], r[5]) for r in f["materials"]],
                tri_material=f["tri_material"],
                sphere_material=f["sphere_material"],
                camera=Camera.from_row(cam) if cam is not None else None,
                light=Light(_row3(light, 0), _row3(light, 3), float(light[6])) if light is not None else None,
                sky=tuple(f["sky"]),
                **_instancing_fields(f),
            )
        except (ValueError, TypeError) as e:
            raise SceneFileError(f"{path}: {e}") from None


#: The arrays of a scene file: dtype kinds and shapes (None: any length).
_FILE_MEMBERS = {
    "format_version": Member("iu", ()),
    "triangles": Member("f", (None, 3, 3)),
    "spheres": Member("f", (None, 4)),
    "materials": Member("f", (None, 6)),
    "tri_material": Member("iu", (None,)),
    "sphere_material": Member("iu", (None,)),
    "sky": Member("f", (3,)),
    "camera": Member("f", (None,)),  # 10 numbers, or 10 + LENS_ROW (Camera.from_row)
    "light": Member("f", (7,)),
    # format 2: meshes 1.. concatenated with their counts, and the instances (Scene.instances)
    "mesh_triangles": Member("f", (None, 3, 3)),
    "mesh_triangle_counts": Member("iu", (None,)),
    "mesh_tri_material": Member("iu", (None,)),  # optional within format 2: material 0 without it
    "instance_mesh": Member("iu", (None,)),
    "instance_transforms": Member("f", (None, 3, 4)),
}
_INSTANCING_MEMBERS = (
    "mesh_triangles",
    "mesh_triangle_counts",
    "mesh_tri_material",
    "instance_mesh",
    "instance_transforms",
)
_IDENTITY = np.array([[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0]], np.float32)


def _instancing_fields(f: dict) -> dict:
    """Scene keyword fields of a file's instancing members (none in a format 1 file)."""
    out: dict = {}
    if ("mesh_triangles" in f) != ("mesh_triangle_counts" in f):
        raise ValueError("mesh_triangles and mesh_triangle_counts are stored together")
    if "mesh_triangles" in f:
        counts = np.asarray(f["mesh_triangle_counts"], np.int64)
        if np.any(counts < 0) or counts.sum() != len(f["mesh_triangles"]):
            raise ValueError(
                f"mesh_triangle_counts {counts.tolist()} do not add up to the {len(f['mesh_triangles'])} mesh triangles"
            )
        tris = np.asarray(f["mesh_triangles"], np.float32)
        out["meshes"] = [np.ascontiguousarray(m) for m in np.split(tris, np.cumsum(counts)[:-1])]
        if "mesh_tri_material" in f:
            materials = np.asarray(f["mesh_tri_material"])
            if len(materials) != len(tris):
                raise ValueError(f"mesh_tri_material has {len(materials)} entries for {len(tris)} mesh triangles")
            out["mesh_tri_material"] = np.split(materials, np.cumsum(counts)[:-1])
    elif "mesh_tri_material" in f:
        raise ValueError("mesh_tri_material is stored with mesh_triangles")
    if ("instance_mesh" in f) != ("instance_transforms" in f):
        raise ValueError("instance_mesh and instance_transforms are stored together")
    if "instance_mesh" in f:
        out["instance_mesh"] = f["instance_mesh"]
        out["instance_transforms"] = np.ascontiguousarray(f["instance_transforms"], np.float32)
    return out


def _moved_spheres(spheres: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Spheres under a transform that keeps them spheres (its linear part a scaled rotation)."""
    a = t[:, :3]
    gram = a.T @ a
    scale2 = gram[0, 0]
    if not np.allclose(gram, scale2 * np.eye(3), rtol=1e-5, atol=1e-6 * max(scale2, 1e-30)):
        raise ValueError("an instance of mesh 0 with spheres must keep them spheres (rotation, uniform scale)")
    centres = spheres[:, :3].astype(np.float64) @ a.T + t[:, 3]
    radii = spheres[:, 3:].astype(np.float64) * np.sqrt(scale2)
    return np.concatenate([centres, radii], 1).astype(np.float32)


def _triangles(scene: Scene, value) -> np.ndarray:
    value = _checks.float32_array("triangles", value, (3, 3))
    _core.validate_geometry(value, None)  # NaN, inf or out of range: names the triangle
    return value


def _spheres(scene: Scene, value) -> np.ndarray:
    value = _checks.float32_array("spheres", value, (4,))
    _core.validate_geometry(np.zeros((0, 3, 3), np.float32), value)
    return value


def _meshes(value) -> list[np.ndarray]:
    if isinstance(value, np.ndarray) or not isinstance(value, (list, tuple)):
        raise TypeError(f"meshes must be a list of float32 (T,3,3) triangle arrays, got {type(value).__name__}")
    out = []
    for k, m in enumerate(value, start=1):
        m = _checks.float32_array(f"mesh {k}", m, (3, 3))
        try:
            _core.validate_geometry(m, None)
        except ValueError as e:
            raise ValueError(f"mesh {k}: {e}") from None
        out.append(m)
    return out


def _mesh_tri_material(value) -> list[np.ndarray]:
    """One (T,) integer array per mesh 1..; checked against the meshes and materials when read
    (Scene.mesh_triangle_material), since either may be set after it."""
    if isinstance(value, np.ndarray) or not isinstance(value, (list, tuple)):
        raise TypeError(f"mesh_tri_material must be a list of (T,) integer arrays, got {type(value).__name__}")
    out = []
    for k, m in enumerate(value, start=1):
        m = np.asarray(m)
        if m.ndim != 1 or not (np.issubdtype(m.dtype, np.integer) or m.size == 0):
            raise ValueError(
                f"mesh_tri_material of mesh {k} must be (T,) integers, got shape {m.shape} dtype {m.dtype}"
            )
        out.append(np.ascontiguousarray(m, np.int32))
    return out


def _instance_mesh(value) -> np.ndarray | None:
    if value is None:
        return None
    value = np.asarray(value)
    if value.ndim != 1 or not (np.issubdtype(value.dtype, np.integer) or value.size == 0):
        raise ValueError(f"instance_mesh must be (N,) integers, got shape {value.shape} dtype {value.dtype}")
    return np.ascontiguousarray(value, np.int32)


def _instance_transforms(value) -> np.ndarray | None:
    if value is None:
        return None
    value = _checks.float32_array("instance_transforms", value, (3, 4))
    bad = np.flatnonzero(~np.isfinite(value).reshape(len(value), -1).all(1))
    if len(bad):
        raise ValueError(f"instance {bad[0]}: the transform has a NaN or infinite entry")
    return value


def _materials(scene: Scene, value) -> list[Material]:
    if value is None or (hasattr(value, "__len__") and len(value) == 0):
        return [Material()]
    if isinstance(value, (str, bytes, Material)) or not hasattr(value, "__iter__"):
        raise TypeError(f"materials must be a list of bvhlab.Material, got {type(value).__name__}")
    return [m if isinstance(m, Material) else Material(*m) for m in value]


def _instance_of(kind: type, name: str):
    def check(scene: Scene, value):
        if value is not None and not isinstance(value, kind):
            raise TypeError(
                f"{name} must be a bvhlab.{kind.__name__} or None, got {type(value).__name__} "
                f"{value!r:.60} (make one with bvhlab.{kind.__name__}(...))"
            )
        return value

    return check


_FIELD_CHECKS = {
    "triangles": _triangles,
    "spheres": _spheres,
    "materials": _materials,
    "tri_material": lambda scene, v: scene._material_index("tri_material", v, len(scene.triangles)),
    "sphere_material": lambda scene, v: scene._material_index("sphere_material", v, len(scene.spheres)),
    "camera": _instance_of(Camera, "camera"),
    "light": _instance_of(Light, "light"),
    "sky": lambda scene, v: _vec3("sky", v),
    "meshes": lambda scene, v: _meshes(v),
    "mesh_tri_material": lambda scene, v: _mesh_tri_material(v),
    "instance_mesh": lambda scene, v: _instance_mesh(v),
    "instance_transforms": lambda scene, v: _instance_transforms(v),
}


def default_camera(bounds) -> Camera:
    """The camera that frames `bounds` (bvhlab.defaults.camera_placement: 45° vertical field of
    view, looking at the centre from the front-upper diagonal)."""
    position, target, up, fov = defaults.camera_placement(bounds)
    return Camera(position, target, up, fov)


def default_light(camera: Camera) -> Light:
    """A point light a little above and to the right of the camera."""
    return Light(defaults.light_position(camera.position, camera.look_at, camera.up))
