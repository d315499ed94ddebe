"""Crytek Sponza, the scene of the report's Table 1 and Figure 6, bundled losslessly.

Crytek Sponza by Frank Meinl (Crytek, 2010), in Morgan McGuire's cleaned-up version (Computer
Graphics Archive, https://casual-effects.com/data), licence CC BY 3.0
(https://creativecommons.org/licenses/by/3.0/). 262,205 of the model's 262,267 triangles: two of
its 383 sub-objects (sponza_02, sponza_04) were missing from the copy it was read from. Units are
1/10 of McGuire's; Y is up.

The bundle (`blender_scenes/sponza.npz`) stores the triangle soup welded: every distinct vertex
(by its exact bits, so welding loses nothing) once, as three coordinate columns, and the corners
as differences of vertex indices in order of first use. Both compress well with LZMA (the zip's
members are LZMA-compressed; `numpy.load` reads them). `unweld` rebuilds the float32 (262205, 3, 3)
array bit for bit, and `load_triangles` checks that against the sha256 of the source `.npy`.
"""

from __future__ import annotations

import hashlib
import io
import zipfile
from pathlib import Path

import numpy as np

from .._atomic import replacing
from ..scene import Camera, Light, Material, Scene

FILE_NAME = "sponza.npz"
TRIANGLES = 262_205
#: sha256 of `sponza_tris.npy` (numpy's .npy format, version 1.0) as it was received.
SOURCE_SHA256 = "e36e2e881611408c59887e68367d318b30365f069b7b193c5eafd37f66653537"
ATTRIBUTION = "Crytek Sponza by Frank Meinl (Crytek), Morgan McGuire's version, CC BY 3.0; 2 of 383 sub-objects missing"

#: A view like the report's Figure 6 (800×600), which gives no camera: ours, along the atrium, showing the
#: whole nave.
CAMERA = Camera(position=(-110.0, 20.0, -4.0), look_at=(100.0, 45.0, 2.0), up=(0.0, 1.0, 0.0), fov_y=60.0)
#: A point light high in the open court, over the middle of the nave (report §2.1: one point light).
LIGHT = Light(position=(10.0, 110.0, 0.0), color=(1.0, 0.95, 0.85), intensity=1.0)
SKY = (0.55, 0.68, 0.85)
STONE = Material((0.78, 0.72, 0.62))


def weld(triangles: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(vertex_columns float32 (3, V), index_deltas int32 (3T,)): distinct vertices by their bits,
    numbered in order of first use, and the corner indices as differences of consecutive ones."""
    corners = np.ascontiguousarray(triangles, np.float32).reshape(-1, 3)
    keys = corners.view(np.dtype((np.void, 12))).ravel()  # exact bits: -0.0 and 0.0 stay apart
    _, first, inverse = np.unique(keys, return_index=True, return_inverse=True)
    order = np.argsort(first, kind="stable")  # number vertices by first use: deltas stay small
    rank = np.empty_like(order)
    rank[order] = np.arange(len(order))
    vertices = corners[first[order]]
    indices = rank[inverse.reshape(-1)].astype(np.int64)
    deltas = np.diff(indices, prepend=0).astype(np.int32)
    return np.ascontiguousarray(vertices.T), deltas


def unweld(vertex_columns: np.ndarray, index_deltas: np.ndarray) -> np.ndarray:
    """The float32 (T, 3, 3) triangles that `weld` took apart."""
    if vertex_columns.ndim != 2 or vertex_columns.shape[0] != 3 or index_deltas.ndim != 1 or len(index_deltas) % 3:
        raise ValueError(f"not a welded mesh: vertex columns {vertex_columns.shape}, index deltas {index_deltas.shape}")
    indices = np.cumsum(index_deltas, dtype=np.int64)
    if len(indices) and (indices.min() < 0 or indices.max() >= vertex_columns.shape[1]):
        raise ValueError("welded mesh refers to vertices it does not have")
    vertices = np.ascontiguousarray(vertex_columns.T, np.float32)
    return np.ascontiguousarray(vertices[indices].reshape(-1, 3, 3))


def npy_sha256(array: np.ndarray) -> str:
    """sha256 of `array` written as numpy writes a `.npy` file (header and data)."""
    buffer = io.BytesIO()
    np.save(buffer, array)
    return hashlib.sha256(buffer.getvalue()).hexdigest()


def write_bundle(triangles: np.ndarray, path: Path) -> Path:
    """Weld `triangles` into an LZMA-compressed `.npz` at `path`, after checking that it rebuilds
    them bit for bit."""
    columns, deltas = weld(triangles)
    if not np.array_equal(unweld(columns, deltas).view(np.uint32), np.asarray(triangles, np.float32).view(np.uint32)):
        raise AssertionError("welding did not round-trip")  # cannot happen unless weld/unweld are broken
    with replacing(path) as f, zipfile.ZipFile(f, "w", compression=zipfile.ZIP_LZMA) as z:  # whole or not at all
        for name, array in (("vertex_columns", columns), ("index_deltas", deltas)):
            buffer = io.BytesIO()
            np.save(buffer, array)
            # a fixed date: the same input gives the same bytes
            member = zipfile.ZipInfo(f"{name}.npy", date_time=(2010, 1, 1, 0, 0, 0))
            member.compress_type = zipfile.ZIP_LZMA
            z.writestr(member, buffer.getvalue())
    return path


def load_triangles(path: Path) -> np.ndarray:
    """The bundled triangles, float32 (262205, 3, 3); ValueError if they are not the source's bits."""
    try:
        with np.load(path, allow_pickle=False) as f:
            triangles = unweld(f["vertex_columns"], f["index_deltas"])
    except (OSError, KeyError, zipfile.BadZipFile) as e:
        raise ValueError(f"{path}: not a readable Sponza bundle ({e})") from None
    if npy_sha256(triangles) != SOURCE_SHA256:
        raise ValueError(f"{path}: the triangles differ from the source (sha256 mismatch)")
    return triangles


def scene(path: Path) -> Scene:
    """Sponza with a camera like the report's Figure 6 (it gives none: ours), one point light over
    the nave and one matte stone material (a primary and a shadow ray a pixel)."""
    return Scene(triangles=load_triangles(path), materials=[STONE], camera=CAMERA, light=LIGHT, sky=SKY)
