"""The cells of a sweep: one scene with one setting, named by a key that hashes the scene's content
and the settings, so that a cell already measured in the output folder is known without running it
(a changed file or setting is a new cell)."""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..library import load_scene, scene_file
from ..library.gltf_checks import gltf_buffers
from .spec import DEFAULT_REPEATS, Setting, SweepSpec

#: Bumped when what a cell measures changes, so old results are not mistaken for new ones.
SCHEMA = 1
_CHUNK = 1 << 20


@dataclass(frozen=True)
class Cell:
    scene: str  # the spec as the loader takes it: a name or a path
    scene_hash: str  # sha256 of the scene's content ("" when it cannot be read: the cell fails)
    setting: Setting
    rays: int
    ray_seed: int
    repeats: int = DEFAULT_REPEATS
    name: str = ""  # the scene's name in tables and plots (scene_names); "" : its file's stem

    @property
    def key(self) -> str:
        what = {
            "schema": SCHEMA,
            "scene": self.scene_hash or f"unreadable:{self.scene}",
            "settings": self.setting.columns(),
            "rays": self.rays,
            "ray_seed": self.ray_seed,
            "repeats": self.repeats,
        }
        return hashlib.sha256(json.dumps(what, sort_keys=True).encode()).hexdigest()[:20]

    def columns(self) -> dict:
        """What names the cell in the table: key, scene, settings as columns."""
        return {
            "key": self.key,
            "scene": self.name or scene_name(self.scene),
            "source": self.scene,
            "scene_hash": self.scene_hash[:16],
            **self.setting.columns(),
            "rays": self.rays,
            "ray_seed": self.ray_seed,
            "repeats": self.repeats,
        }


def plan_cells(spec: SweepSpec) -> list[Cell]:
    """Every cell of the spec, scene by scene, in the grid's order; a scene whose content equals an
    earlier one's (a copied file) is the same cells, measured once."""
    cells: dict[str, Cell] = {}
    names = scene_names(spec.scenes)
    for scene in spec.scenes:
        content = scene_hash(scene)
        for setting in spec.settings:
            cell = Cell(scene, content, setting, spec.rays, spec.ray_seed, spec.repeats, names[scene])
            cells.setdefault(cell.key, cell)
    return list(cells.values())


def scene_name(spec: str) -> str:
    return spec.split(":", 1)[1] if spec.startswith("gen:") else Path(spec).stem


def scene_names(specs) -> dict[str, str]:
    """A name for each scene spec, unique among `specs`: its stem (scene_name), or where two share
    one (a/bunny.obj, b/bunny.stl) as much of its path as tells them apart (the plots and the
    summary group by name: two meshes of one stem were drawn as one scene)."""
    names = {spec: scene_name(spec) for spec in specs}
    for parts in (1, 2, None):
        counts: dict[str, int] = {}
        for name in names.values():
            counts[name] = counts.get(name, 0) + 1
        clashing = [spec for spec, name in names.items() if counts[name] > 1]
        if not clashing:
            break
        for spec in clashing:
            path = Path(spec).parts
            names[spec] = spec if parts is None else "/".join(path[-parts:])
    return names


def scene_hash(spec: str, loaded=None) -> str:
    """sha256 of the file behind `spec` (files, bundled names), or of the scene's arrays for a
    generated scene and a .blend (those of `loaded`, the Scene already made from `spec`, where
    given: not made again); "" when there is nothing to read (a missing file, an unknown name, a
    .blend without bpy: the cell records the error). A .blend's geometry is also in the files it
    links (a library's mesh edited, the sweep reused the cells of the old one) and in what its
    modifiers make of them: what bpy exports of it is what the cells measure."""
    path = scene_file(spec)
    if path is not None and path.suffix.lower() != ".blend":
        if not path.is_file():
            return ""
        files = [path, *gltf_buffers(path)]  # a glTF's buffers are its geometry too
        return (
            hashlib.sha256("".join(_file_hash(f) for f in files).encode()).hexdigest()
            if len(files) > 1
            else _file_hash(path)
        )
    if (path is None and not spec.startswith("gen:")) or (path is not None and not path.is_file()):
        return ""
    try:
        scene = loaded if loaded is not None else load_scene(spec)[0]  # cheap next to the builds
    except (OSError, ValueError, RuntimeError):  # RuntimeError: a .blend without bpy
        return ""
    return arrays_hash(scene)


def arrays_hash(scene) -> str:
    """sha256 of a Scene's geometry: its triangles and spheres, and where it has instances (a .blend's
    linked duplicates and collection instances, its moving objects) every mesh and the instances'
    meshes and transforms; each array's dtype and shape before its bytes, so that no two cut apart
    differently hash alike (two .blend files of instances alone hashed as one empty scene)."""
    digest = hashlib.sha256()
    arrays = [scene.triangles, scene.spheres]
    if scene.is_instanced:
        arrays += [*scene.meshes, *scene.instances()]
    for array in arrays:
        array = np.ascontiguousarray(array)
        digest.update(f"{array.dtype.str}{array.shape};".encode())
        digest.update(array.tobytes())
    return digest.hexdigest()


def _file_hash(path: Path) -> str:
    digest = hashlib.sha256()
    if path.exists() and not path.is_file():  # a FIFO would block the read: hashed as missing
        return ""
    try:
        with open(path, "rb") as f:
            while chunk := f.read(_CHUNK):
                digest.update(chunk)
    except OSError:
        return ""
    return digest.hexdigest()
