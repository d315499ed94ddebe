"""Scenes from the mesh files model repositories publish: OBJ, PLY, STL, glTF and GLB, read by
trimesh (a maintained importer; bvhlab has no parser of its own). Every mesh of the file, placed by
its scene graph, becomes one triangle soup with bvhlab's default camera, light and material.

A file that cannot be read (missing importer, truncated, the wrong format for its extension, NaN or
out-of-range vertices, faces that point past the vertices, no faces at all, a header claiming more
elements than the file could hold) raises SceneFileError (a ValueError) naming the file. Sizes a
header declares are checked against the file's size before trimesh reads it, so a small file cannot
make it allocate gigabytes."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from .._npz import SceneFileError
from ..scene import Scene

#: Suffix → trimesh's file type.
MESH_SUFFIXES = {".obj": "obj", ".ply": "ply", ".stl": "stl", ".gltf": "gltf", ".glb": "glb"}
#: How much of a PLY file may be header (the PLY format has no limit; real headers are < 1 KB).
_MAX_PLY_HEADER = 64 << 10
_STL_HEADER, _STL_TRIANGLE = 84, 50


def is_mesh_file(spec: str) -> bool:
    return Path(spec).suffix.lower() in MESH_SUFFIXES


def load_mesh_file(path) -> Scene:
    """A Scene holding every triangle of the mesh file at `path` (see the module's docstring)."""
    path = Path(path)
    kind = MESH_SUFFIXES.get(path.suffix.lower())
    if kind is None:
        raise SceneFileError(f"{path}: not a mesh file; expected one of {', '.join(MESH_SUFFIXES)}")
    _check_regular_file(path)
    _check_declared_sizes(path, kind)
    triangles = _triangles(path, kind)
    try:
        return Scene(triangles=triangles)
    except ValueError as e:  # a vertex out of range: the core's message names the triangle
        raise SceneFileError(f"{path}: {e}") from None


def _check_regular_file(path: Path) -> None:
    if path.is_dir():
        raise SceneFileError(f"{path} is a folder, not a mesh file")
    if path.exists() and not path.is_file():  # a FIFO would block the reader
        raise SceneFileError(f"{path} is not a regular file (a FIFO, device or socket), not a mesh file")
    path.stat()  # FileNotFoundError / PermissionError as themselves: the CLI prints them


def _triangles(path: Path, kind: str) -> np.ndarray:
    """float32 (T, 3, 3): the faces of every mesh in the file, in world space."""
    try:
        import trimesh
    except ImportError:
        raise SceneFileError(f"{path}: reading {kind} files needs trimesh (pip install 'bvhlab[files]')") from None
    try:
        mesh = trimesh.load(str(path), file_type=kind, force="mesh", process=False)
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


def _checked_triangles(path: Path, vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    if faces.size == 0:
        raise SceneFileError(f"{path} has no triangles (0 faces)")
    if faces.ndim != 2 or faces.shape[1] != 3 or not np.issubdtype(faces.dtype, np.integer):
        raise SceneFileError(f"{path}: faces must be triangles of vertex indices, got shape {faces.shape}")
    if faces.min() < 0 or faces.max() >= len(vertices):
        raise SceneFileError(f"{path}: a face refers to a vertex that does not exist (have {len(vertices)})")
    triangles = vertices[faces]
    bad = ~np.isfinite(triangles).all(axis=(1, 2))
    if bad.any():
        raise SceneFileError(f"{path}: triangle {int(np.argmax(bad))} has a NaN or infinite vertex")
    return np.ascontiguousarray(triangles, np.float32)


def _check_declared_sizes(path: Path, kind: str) -> None:
    """Refuses element counts a header declares that the file's size cannot hold (every PLY element
    takes at least one byte; a binary STL triangle 50): trimesh would otherwise size arrays by them."""
    size = path.stat().st_size
    with open(path, "rb") as f:
        head = f.read(_MAX_PLY_HEADER if kind == "ply" else _STL_HEADER)
    if kind == "ply":
        end = head.find(b"end_header")
        if head.startswith(b"ply") and end < 0:
            raise SceneFileError(f"{path}: no end_header in the first {_MAX_PLY_HEADER} bytes (truncated or not PLY)")
        for name, count in re.findall(rb"^element\s+(\S+)\s+(\d+)", head[:end], re.MULTILINE):
            if int(count) > size:
                raise SceneFileError(
                    f"{path}: the header declares {int(count)} {name.decode(errors='replace')} elements, "
                    f"more than the file's {size} bytes can hold"
                )
    elif kind == "stl" and len(head) == _STL_HEADER and not head.lstrip().startswith(b"solid"):
        count = int.from_bytes(head[80:84], "little")
        if _STL_HEADER + _STL_TRIANGLE * count > size:
            raise SceneFileError(
                f"{path}: the header declares {count} triangles ({_STL_HEADER + _STL_TRIANGLE * count} bytes), "
                f"the file has {size} bytes (truncated?)"
            )
