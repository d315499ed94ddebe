"""A `bvhlab.Scene` as an `.npz` file (no pickled objects): its members, format versions, and the
checked reading of meshes and instances (format 2)."""

from __future__ import annotations

import warnings
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from . import _checks, defaults
from ._npz import MAX_EXPANSION, Member, SceneFileError, read_npz, write_npz
from .scene_parts import Camera, Light, Material, Rays, _row3

if TYPE_CHECKING:
    from .scene import Scene

#: Written by Scene.save; 2 added meshes and instances (issue 34), 3 a material's holdout (a seventh
#: column of `materials`), 4 the rays it is hidden from (an eighth). Files of every version listed in
#: READ_FORMAT_VERSIONS load.
FORMAT_VERSION = 4
READ_FORMAT_VERSIONS = (1, 2, 3, 4)
#: Columns of a file's materials by format: r, g, b, reflective, transparent, ior (, holdout (, the
#: rays it is hidden from: Material.hidden_from's bits)).
_MATERIAL_COLUMNS = {1: 6, 2: 6, 3: 7, 4: len(defaults.MATERIAL)}


def write_scene(scene: Scene, path) -> Path:
    """Writes `scene` as an `.npz` (no pickled objects) that `Scene.load` and the CLI read, exactly at `path`,
    which must end in .npz (never renamed); an existing file is replaced only once the new one
    is complete. Returns the path. A scene whose parts disagree (material indices not one per
    primitive, or naming a material it lacks, after a field was set) raises ValueError and writes
    nothing: its file would not load."""
    path = _checks.output_file(path, (".npz",), "scene file")
    _check_consistent(scene)
    arrays: dict[str, np.ndarray] = {
        "format_version": np.array(FORMAT_VERSION),
        "triangles": scene.triangles,
        "spheres": scene.spheres,
        "materials": np.array([m.as_row() for m in scene.materials], np.float64).reshape(-1, len(defaults.MATERIAL)),
        "tri_material": scene.tri_material,
        "sphere_material": scene.sphere_material,
        "sky": np.array(scene.sky, np.float64),
    }
    if scene.meshes:
        arrays["mesh_triangles"] = np.concatenate(scene.meshes)
        arrays["mesh_triangle_counts"] = np.array([len(m) for m in scene.meshes], np.int64)
        if scene.mesh_tri_material:
            materials = [scene.mesh_triangle_material(k) for k in range(1, scene.mesh_count)]
            arrays["mesh_tri_material"] = np.concatenate(materials)
    if scene.instance_mesh is not None or scene.instance_transforms is not None:
        arrays["instance_mesh"], arrays["instance_transforms"] = scene.instances()
    if scene.camera is not None:
        arrays["camera"] = np.array(scene.camera.as_row(), np.float64)
    if scene.light is not None:
        arrays["light"] = np.array(scene.light.as_row(), np.float64)
    return write_npz(path, arrays)


def read_scene(cls: type[Scene], path, *, max_expansion: float = MAX_EXPANSION) -> Scene:
    """The scene (of class `cls`) written by `write_scene`. Headers are checked before data is read: dtypes, shapes,
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
    version = int(f["format_version"])
    if version not in READ_FORMAT_VERSIONS:
        raise SceneFileError(
            f"{path} is a bvhlab scene of format {version}; "
            f"this version reads formats {', '.join(map(str, READ_FORMAT_VERSIONS))}"
        )
    columns = f["materials"].shape[1]
    if columns != _MATERIAL_COLUMNS[version]:
        raise SceneFileError(
            f"{path}: materials has {columns} columns; a scene of format {version} has {_MATERIAL_COLUMNS[version]}"
        )
    try:
        cam, light = f.get("camera"), f.get("light")
        scene = cls(
            triangles=np.ascontiguousarray(f["triangles"], np.float32),
            spheres=np.ascontiguousarray(f["spheres"], np.float32),
            materials=[_material_of_row(r, path) for r in f["materials"]],
            tri_material=f["tri_material"],
            sphere_material=f["sphere_material"],
            camera=Camera.from_row(cam) if cam is not None else None,
            light=Light(_row3(light, 0), _row3(light, 3), float(light[6])) if light is not None else None,
            sky=tuple(f["sky"]),
            **_instancing_fields(f),
        )
        if scene.is_instanced:  # checked now, naming the file (the Scene checks them when used)
            scene.instances()
            for k in range(1, scene.mesh_count):
                scene.mesh_triangle_material(k)
        return scene
    except (ValueError, TypeError) as e:
        raise SceneFileError(f"{path}: {e}") from None


#: The arrays of a scene file: dtype kinds and shapes (None: any length).
_FILE_MEMBERS = {
    "format_version": Member("iu", ()),
    "triangles": Member("f", (None, 3, 3)),
    "spheres": Member("f", (None, 4)),
    "materials": Member("f", (None, None)),  # _MATERIAL_COLUMNS by format
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


def _check_consistent(scene: Scene) -> None:
    """What Scene.load checks across fields, checked before writing: each kind's material indices
    as setting them checks them (one per primitive, each naming a material), against the fields
    set since."""
    try:
        for k in range(scene.mesh_count):
            scene.mesh_triangle_material(k)  # the other meshes' are checked as they are read
        scene._material_index("tri_material", scene.tri_material, len(scene.triangles))
        scene._material_index("sphere_material", scene.sphere_material, len(scene.spheres))
    except ValueError as e:
        raise ValueError(f"cannot save the scene: {e}") from None


def _material_of_row(row, path) -> Material:
    """A scene file's material; one written before reflective + transparent was bounded by 1 (the
    add-on exported a Principled BSDF of metallic 1 and transmission 1 as 1 and 1) transmits what it
    does not reflect, as the add-on exports it now, with a warning."""
    reflective, transparent = float(row[3]), float(row[4])
    if reflective + transparent > 1.0 + 1e-6 and 0.0 <= reflective <= 1.0:
        warnings.warn(
            f"{path}: a material of reflective {reflective} and transparent {transparent} (more light than "
            f"arrives) is read with transparent {1.0 - reflective:g}",
            stacklevel=3,
        )
        transparent = 1.0 - reflective
    holdout = float(row[6]) if len(row) > 6 else 0.0
    if holdout not in (0.0, 1.0):
        raise ValueError(f"a material's holdout must be 0 or 1, got {holdout}")
    hidden = float(row[7]) if len(row) > 7 else 0.0
    if not (hidden.is_integer() and 0 <= hidden <= int(~Rays(0))):
        raise ValueError(f"a material's hidden rays must be Rays flags (0 to {int(~Rays(0))}), got {hidden}")
    return Material(
        tuple(row[:3]), reflective, transparent, row[5], holdout=bool(holdout), hidden_from=Rays(int(hidden))
    )


def _instancing_fields(f: dict) -> dict:
    """Scene keyword fields of a file's instancing members (none in a format 1 file)."""
    out: dict = {}
    if ("mesh_triangles" in f) != ("mesh_triangle_counts" in f):
        raise ValueError("mesh_triangles and mesh_triangle_counts are stored together")
    if "mesh_triangles" in f:
        counts = np.asarray(f["mesh_triangle_counts"], np.int64)
        total = len(f["mesh_triangles"])
        # each count in range before the sum: counts near 2**62 would wrap it to the total
        if np.any(counts < 0) or np.any(counts > total) or counts.sum() != total:
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
