"""Named scenes: the bundled `.blend` files (blender_scenes/), Crytek Sponza (`sponza`, bundled as
an `.npz`, no Blender needed), generated scenes (`gen:...`, no Blender needed), and files (`.blend`
read through bpy with the add-on's exporter, `.npz`, OBJ, PLY and STL by bvhlab's readers, glTF/GLB
through trimesh: library.files)."""

from __future__ import annotations

import json
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from ..scene import Scene
from . import sponza
from .files import MESH_SUFFIXES, is_mesh_file, load_mesh_file

#: The suffixes of the scene files load_scene reads (in any case), and as a message lists them.
SCENE_FILE_SUFFIXES = (".blend", ".npz", *MESH_SUFFIXES)
FILE_KINDS = ", ".join(SCENE_FILE_SUFFIXES)


def is_scene_file(spec: str) -> bool:
    """Whether load_scene reads `spec` as a file (by its suffix) rather than a scene's name."""
    return Path(spec).suffix.lower() in SCENE_FILE_SUFFIXES


@dataclass(frozen=True)
class SceneInfo:
    name: str
    description: str
    triangles: int
    spheres: int
    source: str  # "bundled .blend", "bundled .npz" or "generated"


def bundled_dir() -> Path | None:
    """blender_scenes/: inside the installed package (wheels) or beside python/ in a checkout."""
    package = Path(__file__).resolve().parents[1]  # bvhlab/
    for candidate in (package / "blender_scenes", package.parents[1] / "blender_scenes"):
        if (candidate / "scenes.json").exists():
            return candidate
    return None


def _bundled() -> dict:
    d = bundled_dir()
    return json.loads((d / "scenes.json").read_text()) if d else {}


def _generated() -> dict[str, tuple[str, Callable[[], Scene]]]:
    from . import procedural, scatter, showcase

    def triangles_scene(make):
        return lambda: Scene(triangles=make())

    return {
        "gen:five_spheres": ("the report's five spheres (Figures 3-4)", showcase.five_spheres),
        "gen:whitted": ("reflective and transparent spheres over a checker floor", showcase.whitted),
        "gen:room": ("a detailed torus knot in a large room, 250k triangles", _room),
        "gen:knot": ("a bumpy torus knot, 250k triangles", triangles_scene(lambda: procedural.torus_knot(250_000))),
        "gen:knot_1m": (
            "a bumpy torus knot, 1M triangles (report Figure 5: over 700,000)",
            triangles_scene(lambda: procedural.torus_knot(1_000_000)),
        ),
        "gen:knot_field": (
            "2000 instances of a 20k-triangle knot and a box over a floor: 20M triangles, a two-level tree",
            scatter.knot_field,
        ),
        "gen:random_spheres": (
            "2000 spheres uniformly at random in a cube (report §4.2)",
            lambda: Scene(spheres=procedural.random_spheres(2000, radius=0.015, seed=1)),
        ),
    }


def _room() -> Scene:
    """procedural.model_in_room seen from inside the room, looking at the knot."""
    from ..scene import Camera, Light
    from . import procedural

    return Scene(
        triangles=procedural.model_in_room(250_000),
        camera=Camera((-25, -40, -20), (20, 25, -50), fov_y=50),
        light=Light((-10, -30, 40)),
    )


def list_scenes() -> list[SceneInfo]:
    out = [
        SceneInfo(k, v.get("description", ""), v.get("triangles", 0), v.get("spheres", 0), "bundled .blend")
        for k, v in _bundled().items()
    ]
    if _sponza_path() is not None:
        out.append(
            SceneInfo(
                "sponza", f"the report's Table 1 scene: {sponza.ATTRIBUTION}", sponza.TRIANGLES, 0, "bundled .npz"
            )
        )
    for name, (description, _) in _generated().items():
        out.append(SceneInfo(name, description, -1, -1, "generated"))
    return out


def load_scene(spec: str) -> tuple[Scene, str]:
    """A Scene from a bundled name, a `gen:` name, or a `.blend`, `.npz`, `.obj`, `.ply`, `.stl`,
    `.gltf` or `.glb` path; and a short name."""
    path = Path(spec)
    if is_mesh_file(spec):
        return load_mesh_file(path), path.stem
    if path.suffix.lower() == ".npz":  # any case, as the mesh files' (S.BLEND: "no scene 'S.BLEND'")
        return Scene.load(path), path.stem
    if path.suffix.lower() == ".blend":
        return _load_blend(path), path.stem
    generated = _generated()
    if spec in generated:
        return generated[spec][1](), spec.split(":", 1)[1]
    sponza_file = _sponza_path() if spec == "sponza" else None
    if sponza_file is not None:
        return sponza.scene(sponza_file), spec
    bundled = _bundled()
    if spec in bundled:
        return _load_blend(bundled_dir() / bundled[spec]["file"]), spec
    names = ", ".join(sorted([*bundled, *generated, *(["sponza"] if _sponza_path() else [])]))
    raise FileNotFoundError(f"no scene '{spec}': give a scene file ({FILE_KINDS}), or one of: {names}")


def scene_file(spec: str) -> Path | None:
    """The file a scene spec reads (a path given, or a bundled name's file); None for `gen:` names
    and for names that do not exist."""
    if is_scene_file(spec):
        return Path(spec)
    if spec == "sponza":
        return _sponza_path()
    bundled = _bundled()
    folder = bundled_dir()
    return folder / bundled[spec]["file"] if folder is not None and spec in bundled else None


def _sponza_path() -> Path | None:
    d = bundled_dir()
    path = d / sponza.FILE_NAME if d else None
    return path if path is not None and path.exists() else None


def _load_blend(path: Path) -> Scene:
    from ..blender.load import load_blend  # needs bpy: imported only for .blend files

    return load_blend(path)
