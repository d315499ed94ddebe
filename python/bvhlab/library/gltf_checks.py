"""What trimesh reads wrong in a glTF 2.0 file (Khronos, glTF 2.0 specification), refused before
it reads it: extensions the file requires that change its geometry or that bvhlab does not know
(Draco and meshopt compression, read as placeholder zeros), GPU instancing (its instances lost),
sparse accessors (their values ignored), normalized quantized positions (read unscaled), triangle
fans (read as no triangles), skinned meshes (placed by their node, which skinning ignores), morph
targets given weight (read in their base shape); and a file that is not glTF at all (not JSON,
empty) named as such rather than as a missing file. Two things it reads wrong are mended instead:
trimesh skips the first node with a camera, and the mesh on it and the nodes below it with it (a
mesh parented to a camera), so trimesh is given the file without its cameras (`without_cameras`);
and it composes deep hierarchies in time cubic in their depth, so those are flattened first
(gltf_nodes.py)."""

from __future__ import annotations

import json
import re
import struct
from pathlib import Path
from urllib.parse import unquote

from .._npz import SceneFileError
from .gltf_nodes import flatten_deep_nodes

#: Required extensions that leave the geometry as the core format says (materials, textures,
#: lights, metadata) or that trimesh reads (KHR_mesh_quantization's non-normalized positions).
_KNOWN_PREFIXES = ("KHR_materials_", "KHR_texture_", "EXT_texture_", "MSFT_texture_", "KHR_lights_")
_KNOWN = {"KHR_mesh_quantization", "KHR_xmp_json_ld"}
_TRIANGLE_FAN = 6
_BOM = b"\xef\xbb\xbf"
#: Primitive extensions that hold the geometry elsewhere: without a fallback (accessors with no
#: buffer view) trimesh reads placeholder zeros.
_COMPRESSED = ("KHR_draco_mesh_compression",)


def _json_text(path: Path, any_suffix: bool = True) -> tuple[str, bytes] | None:
    """("glb" or "gltf", the file's JSON bytes): a GLB's JSON chunk alone (a GLB named .gltf is
    GLB), a .gltf or .glb of JSON whole; None for a file of another suffix unless `any_suffix` (not
    read: a scene file may be gigabytes). Raises SceneFileError for a GLB without its JSON chunk."""
    with open(path, "rb") as f:
        head = f.read(20)
        if head[:4] == b"glTF":
            if len(head) < 20 or head[16:20] != b"JSON":
                raise SceneFileError(f"{path}: a GLB file without its JSON chunk (truncated?)")
            return "glb", f.read(struct.unpack_from("<I", head, 12)[0])
        # a glTF's suffix either way: a JSON glTF saved as .glb is read by its contents (check_gltf)
        # and its buffers are its geometry too (the sweep's cache key missed them: stale figures)
        if not any_suffix and path.suffix.lower() not in (".gltf", ".glb"):
            return None
        return "gltf", head + f.read()


def check_gltf(path: Path) -> tuple[str, bytes | None]:
    """("glb" or "gltf" by the file's contents (a GLB named .gltf is read as GLB), the file as
    trimesh should read it: None for the file itself, else its bytes without cameras and with a
    deep node hierarchy flattened (without_cameras, gltf_nodes)); raises SceneFileError for a file
    bvhlab would read wrong (see the module's docstring)."""
    found = _json_text(path)
    assert found is not None  # every suffix is read
    kind, text = found
    try:
        doc = json.loads(text.decode("utf-8-sig"))
    except (UnicodeDecodeError, ValueError, RecursionError) as e:
        # ValueError: JSONDecodeError, and an integer of more than 4,300 digits; RecursionError:
        # 100,000 nested brackets (both escaped as themselves, naming no file: a helper's audit)
        raise SceneFileError(f"{path} is not glTF: its JSON cannot be read ({type(e).__name__}: {e})") from None
    if not isinstance(doc, dict) or not isinstance(doc.get("asset"), dict):
        raise SceneFileError(f"{path} is not glTF: no 'asset' object")
    try:
        _check(path, doc, _buffer_sizes(path, kind, doc, len(text)))
        flattened = flatten_deep_nodes(path, doc)  # after _check, which reads the nodes as the file has them
    except (TypeError, AttributeError, KeyError, IndexError) as e:  # a value of the wrong JSON type
        raise SceneFileError(f"{path} is not glTF: {type(e).__name__}: {e}") from None
    mended = without_cameras(path, kind, doc, len(text), flattened)
    if mended is None and kind == "gltf" and text.startswith(_BOM):
        # read above as utf-8-sig; trimesh's JSON parse failed on it and it looked for a
        # "model.gltf" instead ("refers to model.gltf, which is missing": a helper's probe)
        return kind, text[len(_BOM) :]
    return kind, mended


def without_cameras(path: Path, kind: str, doc: dict, json_bytes: int, changed: bool = False) -> bytes | None:
    """The file as `doc` holds it, with no node holding a camera; None where no node holds one and
    `doc` was not `changed` otherwise (flattened). trimesh 5 takes the first node with a camera for
    the camera alone, leaving out the mesh on that node and every node
    below it ("No path from world->1" where a mesh is parented to a camera). A camera places no
    geometry, so bvhlab reads the file without them: a .gltf's JSON (its buffers found beside it
    by the caller's resolver), or a GLB with its JSON chunk replaced and its binary chunk kept."""
    nodes = _list(doc, "nodes")
    if not changed and not any("camera" in node for node in nodes):
        return None
    for node in nodes:
        node.pop("camera", None)
    text = json.dumps(doc).encode()
    if kind == "gltf":
        return text
    text += b" " * (-len(text) % 4)  # a GLB chunk is padded to 4 bytes, JSON with spaces
    with open(path, "rb") as f:
        f.seek(20 + json_bytes)
        rest = f.read()  # the chunks after the JSON chunk (the binary buffer), as they are
    chunk = struct.pack("<I4s", len(text), b"JSON") + text
    return struct.pack("<4sII", b"glTF", 2, 12 + len(chunk) + len(rest)) + chunk + rest


def _check(path: Path, doc: dict, sizes: list[int | None]) -> None:
    required = doc.get("extensionsRequired") or []
    if not isinstance(required, list) or not all(isinstance(name, str) for name in required):
        raise SceneFileError(f"{path} is not glTF: extensionsRequired is not a list of names")
    for name in required:
        if name not in _KNOWN and not str(name).startswith(_KNOWN_PREFIXES):
            raise SceneFileError(f"{path} requires the glTF extension {name}, which bvhlab does not read")
    if any("EXT_mesh_gpu_instancing" in _dict(node, "extensions") for node in _list(doc, "nodes")):
        raise SceneFileError(f"{path}: nodes instanced by EXT_mesh_gpu_instancing, which bvhlab does not read")
    # a skinned mesh's vertices follow its skeleton's joints and ignore its node's transform (glTF
    # 2.0 §3.7.3.3); read as a plain mesh, it was placed by the node: 100 units off Blender's import
    skinned = [n for n, node in enumerate(_list(doc, "nodes")) if "skin" in node and "mesh" in node]
    if skinned:
        raise SceneFileError(
            f"{path}: node {skinned[0]} is a skinned mesh, which bvhlab does not read (pose it and "
            "export it without its skin, or apply the armature)"
        )
    _check_morph_weights(path, doc)
    if _list(doc, "meshes") and not _list(doc, "scenes"):  # trimesh read no triangles: "0 faces"
        raise SceneFileError(f"{path} has meshes but no scenes that place them (glTF 2.0: nothing to show)")
    meshes, tables = _list(doc, "meshes"), {key: _list(doc, key) for key in ("accessors", "bufferViews", "buffers")}
    _check_zero_accessors(path, tables["accessors"], sizes)
    for n, node in enumerate(_list(doc, "nodes")):  # trimesh read "0 faces" for a mesh not there
        if "mesh" in node:
            _item(path, meshes, node["mesh"], "mesh", f"node {n}")
    for m, mesh in enumerate(meshes):
        for primitive in _list(mesh, "primitives"):
            where = f"mesh {mesh.get('name') or m}"
            if primitive.get("mode") == _TRIANGLE_FAN:
                raise SceneFileError(f"{path}: {where} has triangle fans (mode 6), which bvhlab does not read")
            position = _primitive_accessor(
                path, tables, sizes, _dict(primitive, "attributes").get("POSITION"), where, False
            )
            indices = _primitive_accessor(path, tables, sizes, primitive.get("indices"), where, True)
            if primitive.get("mode", 4) == 4 and indices.get("count", 0) % 3:  # "cannot reshape array of size 8"
                raise SceneFileError(
                    f"{path}: {where} has {indices['count']} indices of triangles, not a multiple of 3"
                )
            compressed = [name for name in _COMPRESSED if name in _dict(primitive, "extensions")]
            if compressed and position and "bufferView" not in position:
                # an extension the file uses but does not require (the Draco extension's rules ask
                # for a fallback then; files without one exist): read as zeros, exit 0 (a probe)
                raise SceneFileError(
                    f"{path}: {where} is compressed by {compressed[0]} without uncompressed data, which bvhlab "
                    "does not read (export it without compression)"
                )
            if position and "bufferView" not in position and not compressed:
                # all zeros (§3.6.2.3): degenerate triangles at the origin, as many as it says
                raise SceneFileError(f"{path}: {where}'s positions have no buffer view (all zeros)")
            if position.get("normalized"):
                raise SceneFileError(f"{path}: {where}: normalized positions (KHR_mesh_quantization) are not read")
            if "sparse" in position or "sparse" in indices:
                raise SceneFileError(f"{path}: {where}: sparse accessors are not read")


_COMPONENT_BYTES = {5120: 1, 5121: 1, 5122: 2, 5123: 2, 5125: 4, 5126: 4}
_TYPE_COMPONENTS = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT2": 4, "MAT3": 9, "MAT4": 16}
_INDEX_TYPES = (5121, 5123, 5125)  # unsigned byte, short, int (glTF 2.0 §3.7.2.1)


def _item(path: Path, items: list, index, what: str, where: str) -> dict:
    """items[index], which `where` refers to; SceneFileError where the file has no such item."""
    if not isinstance(index, int) or not 0 <= index < len(items):
        raise SceneFileError(f"{path}: {where} refers to {what} {index!r}, which the file does not have ({len(items)})")
    return items[index]


def _primitive_accessor(path: Path, tables: dict, sizes: list[int | None], index, where: str, indices: bool) -> dict:
    """The accessor `index` of a primitive of mesh `where` (its POSITION, or its `indices`), {} for
    none, checked as trimesh's reader asserts without saying what (its message was
    "AssertionError"): it, its buffer view and buffer exist, the view lies in its buffer (as the
    file declares it and as many bytes as the file holds: `sizes`, _buffer_sizes) and the accessor
    in its view, and indices are unsigned integers. `tables`: the file's accessors, buffer views
    and buffers (made once by the caller; made for each primitive, 20,000 meshes took 27 s: a probe)."""
    if index is None:
        return {}
    role = "indices" if indices else "POSITION"
    accessor = _item(path, tables["accessors"], index, "accessor", f"{where}'s {role}")
    component, kind = accessor.get("componentType"), accessor.get("type")
    if indices and component not in _INDEX_TYPES:
        raise SceneFileError(
            f"{path}: {where}'s indices have component type {component!r}: glTF indices are unsigned bytes, "
            "shorts or ints (5121, 5123, 5125)"
        )
    if not indices and kind != "VEC3":  # VEC2: "triangles must have shape (N, 3, 3)"; VEC4: "a face refers to..."
        raise SceneFileError(f"{path}: {where}'s positions are {kind!r}, not VEC3 (glTF 2.0 §3.7.2.1)")
    if "bufferView" not in accessor:
        return accessor  # all zeros (glTF 2.0 §3.6.2.3)
    v = accessor["bufferView"]
    view = _item(path, tables["bufferViews"], v, "buffer view", f"accessor {index}")
    buffer = _item(path, tables["buffers"], view.get("buffer"), "buffer", f"buffer view {v}")
    start, length, room = view.get("byteOffset", 0), view.get("byteLength", 0), buffer.get("byteLength", 0)
    for name, value in (("byteOffset", start), ("byteLength", length)):
        _natural(path, f"buffer view {v}'s {name}", value)  # -60 was read from the buffer's end
    if start + length > room:
        raise SceneFileError(
            f"{path}: buffer view {v} ({start} + {length} bytes) runs past the end of buffer "
            f"{view.get('buffer')} ({room} bytes)"
        )
    held = sizes[view["buffer"]]
    if held is not None and start + length > held:  # trimesh: "AssertionError", "list index out of range"
        raise SceneFileError(
            f"{path}: buffer view {v} ({start} + {length} bytes) runs past the {held} bytes the file holds for "
            f"buffer {view.get('buffer')} (declared {room}: truncated?)"
        )
    size = _COMPONENT_BYTES.get(component, 0) if isinstance(component, int) else 0
    size *= _TYPE_COMPONENTS.get(kind, 0) if isinstance(kind, str) else 0
    count, offset = accessor.get("count", 0), accessor.get("byteOffset", 0)
    stride = view.get("byteStride", size)
    _natural(path, f"accessor {index}'s count", count)  # -1 read every vertex but the last
    _natural(path, f"accessor {index}'s byteOffset", offset)
    if not isinstance(stride, int) or not size <= stride <= 252:  # §3.6.2.4 (4 overlapped a VEC3's floats)
        raise SceneFileError(
            f"{path}: buffer view {v}'s byteStride {stride!r} is not {size} to 252 bytes (accessor {index}'s "
            f"elements are {size} bytes)"
        )
    end = offset + (count - 1) * stride + size if count else 0
    if end > length:
        raise SceneFileError(
            f"{path}: accessor {index} ({count} elements, {end} bytes) runs past the end of buffer view {v} "
            f"({length} bytes)"
        )
    return accessor


def _natural(path: Path, what: str, value) -> None:
    if not isinstance(value, int) or value < 0:
        raise SceneFileError(f"{path}: {what} is {value!r}, not a count of 0 or more")


def _check_zero_accessors(path: Path, accessors: list[dict], sizes: list[int | None]) -> None:
    """An accessor without a buffer view is zeros (§3.6.2.3), which trimesh makes for every one of
    them, used or not: refused where it holds more bytes than the file's buffers do (600 bytes of
    JSON declaring 30M positions took 4.7 GB; 2^40 ran out of memory: a helper's audit)."""
    held = sum(size for size in sizes if size is not None)
    for k, accessor in enumerate(accessors):
        if "bufferView" in accessor:
            continue
        count, component, kind = accessor.get("count", 0), accessor.get("componentType"), accessor.get("type")
        _natural(path, f"accessor {k}'s count", count)
        size = _COMPONENT_BYTES.get(component, 4) if isinstance(component, int) else 4
        size *= _TYPE_COMPONENTS.get(kind, 16) if isinstance(kind, str) else 16
        if count * size > max(held, 1 << 16):
            raise SceneFileError(
                f"{path}: accessor {k} declares {count} elements of zeros (no buffer view), {count * size} bytes, "
                f"more than the file's buffers hold ({held})"
            )


def _buffer_sizes(path: Path, kind: str, doc: dict, json_bytes: int) -> list[int | None]:
    """The bytes each buffer of the file holds (not its declared byteLength): a data: URI's decoded
    payload, a file's size, a GLB's binary chunk for the buffer without a URI (0 in a .gltf, or a
    GLB without that chunk); None where that is not known here (a file that is not there: the
    loader says it is missing; a URL: refused by the loader)."""
    sizes: list[int | None] = []
    for buffer in _list(doc, "buffers"):  # as _item indexes them
        uri = buffer.get("uri")
        if not isinstance(uri, str):
            sizes.append(_glb_binary_bytes(path, json_bytes) if kind == "glb" else 0)
        elif uri.startswith("data:"):
            payload = uri.partition(",")[2]
            sizes.append(len(payload) * 3 // 4 - payload[-2:].count("=") if ";base64," in uri else None)
        else:
            where = referenced_path(path, uri)
            sizes.append(where.stat().st_size if where is not None and where.is_file() else None)
    return sizes


def _glb_binary_bytes(path: Path, json_bytes: int) -> int:
    """The length of a GLB's binary chunk (the one after its JSON chunk), 0 where there is none."""
    with open(path, "rb") as f:
        f.seek(20 + json_bytes)
        head = f.read(8)
        if len(head) < 8 or head[4:8] != b"BIN\0":
            return 0
        stated = struct.unpack_from("<I", head)[0]
        f.seek(0, 2)
        return min(stated, f.tell() - (28 + json_bytes))


def _check_morph_weights(path: Path, doc: dict) -> None:
    """Morph targets shown with a weight (a node's `weights`, else its mesh's; glTF 2.0 §3.7.2.2)
    change the shape, which trimesh reads without them; at weight 0 (the default) the base shape is
    what is shown."""
    found = doc.get("meshes")
    meshes: list = found if isinstance(found, list) else []
    for n, node in enumerate(_list(doc, "nodes")):
        m = node.get("mesh")
        if not isinstance(m, int) or not 0 <= m < len(meshes) or not isinstance(meshes[m], dict):
            continue
        mesh = meshes[m]
        if not any(_list(p, "targets") for p in _list(mesh, "primitives")):
            continue
        weights = node.get("weights") or mesh.get("weights") or []
        if any(w != 0 for w in weights if isinstance(w, (int, float))):
            raise SceneFileError(
                f"{path}: node {n} shows mesh {mesh.get('name') or m} with morph target weights {weights}, which "
                "bvhlab does not apply (it would read the base shape; apply the shape keys before exporting)"
            )


def _list(doc: dict, key: str) -> list[dict]:
    value = doc.get(key) or []
    return [v for v in value if isinstance(v, dict)] if isinstance(value, list) else []


def _dict(doc: dict, key: str) -> dict:
    value = doc.get(key)
    return value if isinstance(value, dict) else {}


def gltf_buffers(path: Path) -> list[Path]:
    """The files a glTF's or GLB's buffers are in (not data: URIs), in its order; [] for anything
    else or a file that cannot be read (the loader says why). What a cache of its geometry hashes."""
    return _referenced(path, ("buffers",))


def gltf_files(path: Path) -> list[Path]:
    """Every file a glTF or GLB refers to that its loader opens: its buffers' and its images'
    (each checked before trimesh opens it: a FIFO blocked the read)."""
    return _referenced(path, ("buffers", "images"))


def _referenced(path: Path, kinds: tuple[str, ...]) -> list[Path]:
    try:
        found = _json_text(path, any_suffix=False)
        if found is None:
            return []
        doc = json.loads(found[1].decode("utf-8-sig"))
    except (OSError, SceneFileError, UnicodeDecodeError, json.JSONDecodeError):
        return []
    if not isinstance(doc, dict):
        return []
    uris = [item.get("uri") for kind in kinds for item in _list(doc, kind)]
    paths = [referenced_path(path, u) for u in uris if isinstance(u, str)]
    return [p for p in paths if p is not None]


# a URI's scheme (RFC 3986 §3.1; two letters at least: "C:" is a drive), or a network-path
# reference ("//host/share/buf.bin", §4.2: a UNC path on Windows)
_SCHEME = re.compile(r"[A-Za-z][A-Za-z0-9+.-]+:|//|\\\\")


def referenced_path(gltf: Path, uri: str) -> Path | None:
    """The file a URI of the glTF at `gltf` refers to, the one its loader reads (files.py
    _uri_resolver) and its checks and the sweep's cache look at: the URI resolved against the
    glTF's folder (RFC 3986: "../shared/buf.bin" in the folder beside it, an absolute path where it
    says), its query and fragment ("?v=2", "#part") left out (unless only the file named with them
    is there: a "#" its exporter did not encode) and percent-decoded as uri_name reads it; None for
    a data: URI or a URL (http:, file:, //host/...), which name no file here."""
    if _SCHEME.match(uri):
        return None
    folder = gltf.parent
    path = folder / uri_name(folder, re.split(r"[?#]", uri, maxsplit=1)[0])
    whole = folder / uri_name(folder, uri)
    return whole if not path.exists() and whole.exists() else path


def uri_name(folder: Path, uri: str) -> str:
    """The name of the file a glTF URI refers to in `folder` (the loader's and the sweep cache's
    one answer): percent-decoded, as URIs are RFC 3986 references (the glTF 2.0 specification,
    "URIs": Blender writes the buffer of "my model.gltf" as "my%20model.bin"), or as written where
    only that file is there (a "%" its exporter did not encode, "a%20b.bin" on disk)."""
    decoded = unquote(uri)
    if decoded != uri and not (folder / decoded).exists() and (folder / uri).exists():
        return uri
    return decoded
