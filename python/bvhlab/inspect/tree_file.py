"""Trees saved to files (issue 35): `save_bvh` (Bvh.save) and `load_bvh`, so that a tree built
once can be inspected or rendered again without building it again.

A tree file (suffix .bvhtree) is, in order: MAGIC (12 bytes); the format version and the length
of the header (two little-endian uint32); the header (UTF-8 JSON: the geometry's fingerprint and
primitive counts, the build settings, the build time, the node and reference counts); the nodes
(32 bytes each, NODE_DTYPE); the references (uint32); a SHA-256 of everything before it. The
leaf-ordered geometry and the depths are made again on load, from the scene and the nodes, and
every invariant of the tree is checked in C++ (core_cpp/include/bvhlab/restore.h)."""

from __future__ import annotations

import hashlib
import json
import math
import struct
from pathlib import Path

import numpy as np

from .. import _atomic, _checks, _core

MAGIC = b"bvhlab tree\n"
#: The version this bvhlab writes and reads; any change to the layout above adds 1.
FORMAT_VERSION = 1
SUFFIX = ".bvhtree"
_PREFIX = struct.Struct("<II")  # version, header length
_DIGEST = 32


class TreeFileError(ValueError):
    """A tree file that cannot be loaded: not a tree file, another version, cut short or damaged,
    or saved for other geometry or other build settings."""


def save_bvh(bvh, path) -> Path:
    """Writes `bvh` to `path`, which must end in .bvhtree (never renamed; a scene's .npz or any
    other file is not overwritten by a tree), as a whole or not at all (a WriteError leaves what
    was there). Raises OutputPathError for another name, a folder or a folder that cannot be
    written, before any work."""
    path = tree_path(path)
    digest = hashlib.sha256()
    with _atomic.replacing(path) as f:
        for part in _tree_parts(bvh):
            digest.update(part)
            f.write(part)
        f.write(digest.digest())
    return path


def tree_path(path) -> Path:
    """`path` checked as a tree file's (a name ending in .bvhtree, in a folder that can be written):
    OutputPathError otherwise."""
    return _checks.output_file(path, (SUFFIX,), "tree file")


def tree_bytes(bvh) -> bytes:
    """The file save_bvh writes, as bytes (for a caller that writes it together with other files:
    `bvhlab inspect --save-tree --json`)."""
    body = b"".join(_tree_parts(bvh))
    return body + hashlib.sha256(body).digest()


def _tree_parts(bvh) -> tuple[bytes, ...]:
    """The file's parts before its digest: magic, version and header length, header, nodes, refs."""
    # every part from one version of the tree: read one by one, a refit, update or optimize on
    # another thread could mix two versions into a file that does not load
    parts = bvh._core.file_parts()
    nodes = np.ascontiguousarray(parts["nodes"]).view(np.uint8)
    refs = np.ascontiguousarray(parts["refs"], dtype="<u4")
    header = {
        "format_version": FORMAT_VERSION,
        "geometry_fingerprint": int(parts["geometry_fingerprint"]),
        "triangles": int(parts["triangles"]),
        "spheres": int(parts["spheres"]),
        "nodes": int(len(nodes)),
        "refs": int(len(refs)),
        "config": bvh.config.tree_settings(),
        "build_ms": float(parts["build_ms"]),
    }
    head = json.dumps(header, sort_keys=True).encode()
    return MAGIC, _PREFIX.pack(FORMAT_VERSION, len(head)), head, nodes.tobytes(), refs.tobytes()


def load_bvh(path, scene_or_triangles, spheres=None, *, config=None):
    """The tree saved in `path`, over the geometry it was built for (a bvhlab.Scene, or triangles
    and spheres as for bvhlab.build). With `config` (a BuildConfig), the saved tree must have
    been built with those settings. Raises TreeFileError (a ValueError) for a file that is not a
    tree file, of another format version, cut short or damaged, or saved for other geometry or
    other settings; OSError when it cannot be read."""
    from ..build_config import BuildConfig
    from ..bvh import Bvh
    from ..scene import Scene

    if isinstance(scene_or_triangles, Scene):
        if spheres is not None:
            raise ValueError("pass spheres inside the Scene, not beside it")
        if scene_or_triangles.is_instanced:  # its own triangles are mesh 0's alone: a tree of them
            # loaded silently, and missed every other instance
            raise TreeFileError(
                f"{path} holds a flat tree, and this scene has instances (a two-level tree), whose trees "
                "are not saved to a file"
            )
        triangles, spheres = scene_or_triangles.triangles, scene_or_triangles.spheres
    else:
        triangles = scene_or_triangles
    triangles = _checks.float32_array("triangles", triangles, (3, 3))
    if spheres is not None:
        spheres = _checks.float32_array("spheres", spheres, (4,))
    if config is not None and not isinstance(config, BuildConfig):
        raise TypeError(f"config must be a bvhlab.BuildConfig, got {type(config).__name__}")
    path = Path(path)
    header, nodes, refs = _read(path)
    counts = (len(triangles), 0 if spheres is None else len(spheres))
    if counts != (header["triangles"], header["spheres"]):
        raise TreeFileError(
            f"{path} was saved for other geometry: {header['triangles']} triangles and {header['spheres']} "
            f"spheres, this scene has {counts[0]} and {counts[1]}"
        )
    try:
        saved_config = BuildConfig(**header["config"])
    except (TypeError, ValueError) as e:
        raise TreeFileError(f"{path} has build settings this bvhlab does not know: {e}") from None
    if config is not None and config != saved_config:
        raise TreeFileError(f"{path} was built with {_settings_text(saved_config)}, not with {_settings_text(config)}")
    try:
        core = _core.restore_bvh(
            nodes,
            refs,
            triangles,
            spheres,
            saved_config.core(),
            float(header["build_ms"]),
            int(header["geometry_fingerprint"]),
        )
    except ValueError as e:
        raise TreeFileError(f"{path}: {e}") from None
    return Bvh(core, saved_config)


def _read(path: Path) -> tuple[dict, np.ndarray, np.ndarray]:
    _checks.input_file(path, "tree file", TreeFileError)
    data = path.read_bytes()
    if not data.startswith(MAGIC):
        raise TreeFileError(f"{path} is not a bvhlab tree file")
    start = len(MAGIC) + _PREFIX.size
    if len(data) < start:
        raise TreeFileError(f"{path} is cut short (no header)")
    version, head_len = _PREFIX.unpack_from(data, len(MAGIC))
    if version != FORMAT_VERSION:
        raise TreeFileError(
            f"{path} is a bvhlab tree file of format version {version}; this bvhlab reads version {FORMAT_VERSION}"
        )
    if len(data) < start + head_len + _DIGEST:
        raise TreeFileError(f"{path} is cut short ({len(data)} bytes)")
    if hashlib.sha256(data[:-_DIGEST]).digest() != data[-_DIGEST:]:
        raise TreeFileError(f"{path} is cut short or damaged (its checksum does not match)")
    try:
        header = json.loads(data[start : start + head_len])
        n_nodes, n_refs = int(header["nodes"]), int(header["refs"])
        missing = [k for k in ("geometry_fingerprint", "triangles", "spheres", "config", "build_ms") if k not in header]
        if missing:
            raise KeyError(", ".join(missing))
        # each field of its type and range (a crafted fingerprint of 2^70 raised nanobind's
        # TypeError, a build_ms of null a TypeError, triangles of "100" said "saved for 100
        # triangles, this scene has 100")
        for key in ("triangles", "spheres", "geometry_fingerprint"):
            if type(header[key]) is not int or not 0 <= header[key] < 2**64:
                raise ValueError(f"{key} is {header[key]!r}, not a whole number of 64 bits")
        if type(header["build_ms"]) not in (int, float) or not math.isfinite(header["build_ms"]):
            raise ValueError(f"build_ms is {header['build_ms']!r}, not a number")
        if not isinstance(header["config"], dict):
            raise ValueError(f"config is {header['config']!r}, not a table of settings")
    # OverflowError: int(inf), isfinite(10**400); RecursionError: a header nested 100,000 deep
    except (ValueError, KeyError, TypeError, AttributeError, OverflowError, RecursionError) as e:
        raise TreeFileError(f"{path} has a damaged header ({type(e).__name__}: {e})") from None
    body = start + head_len
    node_bytes = n_nodes * _core.NODE_BYTES
    if n_nodes < 0 or n_refs < 0 or len(data) - _DIGEST - body != node_bytes + 4 * n_refs:
        raise TreeFileError(f"{path} holds other lengths than its header says")
    nodes = np.frombuffer(data, np.uint8, node_bytes, body).reshape(n_nodes, _core.NODE_BYTES)
    refs = np.frombuffer(data, "<u4", n_refs, body + node_bytes)
    return header, np.ascontiguousarray(nodes), np.ascontiguousarray(refs)


def _settings_text(config) -> str:
    return ", ".join(f"{k}={v}" for k, v in config.tree_settings().items())
