"""Scenes from the mesh files model repositories publish: OBJ, PLY and STL read by bvhlab's own
readers (obj_reader.py, ply_reader.py, stl_reader.py: trimesh's lost a concave polygon's shape,
resolved OBJ's relative indices from the file's end and refused Blender's binary PLY), glTF and GLB
by trimesh after gltf_checks.py refuses what trimesh would read wrong. Every mesh of the file,
placed by its scene graph, becomes one triangle soup with bvhlab's default camera, light and
material.

A file that cannot be read (missing importer, truncated, the wrong format for its extension, NaN or
out-of-range vertices, faces that point past the vertices, no faces at all, a header claiming more
elements than the file holds) raises SceneFileError (a ValueError) naming the file."""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np

from .. import _checks
from .._npz import SceneFileError
from ..scene import Scene
from .gltf_checks import check_gltf, gltf_files, referenced_path
from .obj_reader import read_obj
from .ply_reader import read_ply
from .stl_reader import read_stl

#: Suffix → file type.
MESH_SUFFIXES = {".obj": "obj", ".ply": "ply", ".stl": "stl", ".gltf": "gltf", ".glb": "glb"}
_READERS = {"obj": read_obj, "ply": read_ply, "stl": read_stl}


def is_mesh_file(spec: str) -> bool:
    return Path(spec).suffix.lower() in MESH_SUFFIXES


def load_mesh_file(path) -> Scene:
    """A Scene holding every triangle of the mesh file at `path` (see the module's docstring)."""
    path = Path(path)
    kind = MESH_SUFFIXES.get(path.suffix.lower())
    if kind is None:
        raise SceneFileError(f"{path}: not a mesh file; expected one of {', '.join(MESH_SUFFIXES)}")
    _check_regular_file(path)
    with open(path, "rb") as f:
        if f.read(2) == b"\x1f\x8b":  # every reader saw no faces in it: "has no triangles (0 faces)"
            raise SceneFileError(f"{path} is gzip-compressed: decompress it first (gunzip)")
    if kind in _READERS:
        try:
            vertices, faces = _READERS[kind](path)
        except SceneFileError:
            raise
        except (ValueError, OverflowError) as e:  # a number that is not one, a count numpy refuses
            raise SceneFileError(f"{path} cannot be read as {kind.upper()}: {e}") from None
        triangles = _checked_triangles(path, vertices, faces)
    else:
        triangles = _triangles(path, kind)
    try:
        return Scene(triangles=triangles)
    except ValueError as e:  # a vertex out of range: the core's message names the triangle
        raise SceneFileError(f"{path}: {e}") from None


def _check_regular_file(path: Path) -> None:
    _checks.input_file(path, "mesh file", SceneFileError)
    path.stat()  # FileNotFoundError / PermissionError as themselves: the CLI prints them


def _triangles(path: Path, kind: str) -> np.ndarray:
    """float32 (T, 3, 3): the faces of every mesh in the file, in world space."""
    try:
        import trimesh
    except ImportError:
        raise SceneFileError(f"{path}: reading {kind} files needs trimesh (pip install 'bvhlab[files]')") from None
    kind, mended = check_gltf(path)  # "gltf" or "glb" by the file's contents; mended: without cameras
    for referenced in gltf_files(path):  # a FIFO buffer or image would block trimesh's read
        _checks.input_file(referenced, "file a glTF refers to", SceneFileError)
    try:
        resolver = _uri_resolver(trimesh, path)  # the files it refers to, found beside it
        source = str(path) if mended is None else io.BytesIO(mended)
        mesh = trimesh.load(source, file_type=kind, force="mesh", process=False, resolver=resolver)
        vertices = np.asarray(getattr(mesh, "vertices", np.zeros((0, 3))), np.float64)
        faces = getattr(mesh, "faces", None)  # a point cloud has none
        faces = np.zeros((0, 3), np.int64) if faces is None else np.asarray(faces)
    except FileNotFoundError as e:  # the file was there (_check_regular_file): one it refers to is not
        if not path.exists():
            raise
        missing = e.filename or str(e).strip() or "a file"
        raise SceneFileError(f"{path} refers to {missing}, which is missing (a glTF's buffer or image?)") from None
    except (PermissionError, MemoryError):
        raise
    except Exception as e:  # a third-party parser on hostile input: any of its errors is "cannot read"
        reason = str(e).strip() or type(e).__name__
        raise SceneFileError(f"{path} cannot be read as {kind.upper()}: {reason}") from None
    return _checked_triangles(path, vertices, faces)


def _uri_resolver(trimesh, path: Path):
    """trimesh's resolver for the files a glTF refers to, each read where its URI says
    (gltf_checks.referenced_path: what gltf_files checked before the read, and the sweep's cache
    hashes). trimesh's own read a file of the same name beside the glTF where the URI led out of
    its folder ("../shared/buf.bin", an absolute path, a URL): another file's triangles, silently,
    or a FIFO there that the check had not seen, which blocked. A URL is refused."""

    class Exact(trimesh.resolvers.FilePathResolver):
        def get(self, name: str):
            where = referenced_path(path, name)
            if where is None:  # a data: URI that is not base64 holds the buffer: its start names it
                shown = name if len(name) <= 80 else name[:60] + f"... ({len(name)} characters)"
                raise SceneFileError(f"it refers to {shown!r}, a URL: only files are read")
            return where.read_bytes()  # FileNotFoundError: "refers to ..., which is missing"

    return Exact(str(path))


def _checked_triangles(path: Path, vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    if faces.size == 0:
        raise SceneFileError(f"{path} has no triangles (0 faces)")
    if faces.ndim != 2 or faces.shape[1] != 3 or not np.issubdtype(faces.dtype, np.integer):
        raise SceneFileError(f"{path}: faces must be triangles of vertex indices, got shape {faces.shape}")
    if faces.min() < 0 or faces.max() >= len(vertices):
        raise SceneFileError(f"{path}: a face refers to a vertex that does not exist (have {len(vertices)})")
    triangles = vertices[faces]
    bad = ~(np.abs(triangles) <= np.finfo(np.float32).max).all(axis=(1, 2))  # NaN fails too
    if bad.any():
        raise SceneFileError(f"{path}: triangle {int(np.argmax(bad))} has a NaN, infinite or out-of-range vertex")
    return np.ascontiguousarray(triangles, np.float32)
