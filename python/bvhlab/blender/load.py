"""Reading a `.blend` file outside Blender: open it with bpy (Blender as a Python module) and export
it with the same code the add-on uses."""

from __future__ import annotations

import os
import re
import sys
from pathlib import Path

from .. import _checks
from .._atomic import interrupts_held
from .._npz import SceneFileError
from ..scene import Scene


def bpy_module():
    """Blender's Python module, or RuntimeError saying how to install it. A Ctrl-C while it loads
    (Blender enabling its add-ons, which prints and swallows the KeyboardInterrupt: the command then
    ran on and exited 0) is held back and raised once it is in."""
    try:
        with interrupts_held():
            import bpy
    except ImportError as e:
        raise RuntimeError(
            "reading .blend files needs Blender's Python module: pip install bpy (4.2 to "
            "5.0 for Python 3.11, 5.1 and later for Python 3.13)"
        ) from e
    return bpy


def open_blend(path: Path):
    """bpy.ops.wm.open_mainfile without the UI, a Ctrl-C held as bpy_module holds it (opening a
    file enables add-ons again), and Blender's "Read blend: ..." line sent to stderr: a command's
    stdout is its own output (the line stood before a build's figures). A file bpy cannot read is a
    SceneFileError saying why (bpy's own "Error: ...\n" was passed on as it was: `bvhlab animate`
    printed "error: Error: ..." and a blank line). Returns bpy (bpy_module), imported after the
    path's check (a folder or a FIFO is refused before the second bpy takes to load)."""
    _checks.input_file(path, ".blend file", SceneFileError)  # a FIFO blocked bpy's open
    bpy = bpy_module()
    sys.stdout.flush()
    saved = os.dup(1)
    try:
        os.dup2(2, 1)
        with interrupts_held():
            bpy.ops.wm.open_mainfile(filepath=str(Path(path).resolve()), load_ui=False)
    except RuntimeError as e:  # bpy's "Error: File format is not supported in file '…'\n"
        reason = str(e).strip().removeprefix("Error:").strip()
        saved_by = saved_by_version(path)
        if saved_by is not None and saved_by > tuple(bpy.app.version[:2]):
            # bpy 4.2 calls a 5.0 file "not a blend file" (a helper's probe)
            reason = (
                f"it was saved by Blender {saved_by[0]}.{saved_by[1]}, newer than this bpy "
                f"{bpy.app.version_string} (open it with bpy {saved_by[0]}.{saved_by[1]} or later; bpy says: {reason})"
            )
        raise SceneFileError(f"{path} cannot be read as a .blend file: {reason}") from None
    finally:
        sys.stdout.flush()
        os.dup2(saved, 1)
        os.close(saved)
    _refuse_missing_links(bpy, path)
    return bpy


#: The data a scene's geometry is made of, which a .blend may link from another file.
_LINKABLE = ("objects", "meshes", "collections", "node_groups", "materials", "curves", "metaballs")


def _refuse_missing_links(bpy, path: Path) -> None:
    """SceneFileError where the file links a library that is missing, or data its library no longer
    holds (renamed or deleted there): Blender opens it with that data left out and says so on
    stderr only, and a build and a sweep's rows said "ok" for a scene without that geometry (a
    helper's probe; the review's, for data renamed in a library that is there)."""
    libraries = [library.filepath for library in bpy.data.libraries if getattr(library, "is_missing", False)]
    if libraries:
        one = len(libraries) == 1
        raise SceneFileError(
            f"{path} links {len(libraries)} .blend {'library' if one else 'libraries'} that "
            f"{'is' if one else 'are'} missing: {', '.join(libraries)} (put {'it' if one else 'them'} back "
            "where the file says, or make the linked data local)"
        )
    lost = [
        f"{kind[:-1] if kind != 'meshes' else 'mesh'} '{item.name}' from {item.library.filepath}"
        for kind in _LINKABLE
        for item in getattr(bpy.data, kind, ())
        if item.library is not None and getattr(item, "is_missing", False)
    ]
    if lost:
        raise SceneFileError(
            f"{path} links data its library no longer holds: {', '.join(lost[:3])}"
            + (f" and {len(lost) - 3} more" if len(lost) > 3 else "")
            + " (renamed or deleted there?)"
        )


#: A .blend's header: "BLENDER", then the pointer size and byte order and a 3-digit version
#: ("BLENDER-v402"), or (Blender 5.0's format) a header size and format version and a 4-digit
#: version ("BLENDER17-01v0500"). A compressed file (zstd, gzip) starts otherwise: None.
_HEADER = re.compile(rb"BLENDER(?:[_-][vV](\d)(\d\d)|\d\d-\d\d[vV](\d\d)(\d\d))")


def saved_by_version(path: Path) -> tuple[int, int] | None:
    """(major, minor) of the Blender that saved the .blend at `path`, from its header; None where
    the header does not say (compressed, or not a .blend)."""
    try:
        with open(path, "rb") as f:
            head = f.read(17)
    except OSError:
        return None
    found = _HEADER.match(head)
    if found is None:
        return None
    major, minor = (found.group(1), found.group(2)) if found.group(1) else (found.group(3), found.group(4))
    return int(major), int(minor)


def load_blend(path: Path) -> Scene:
    """Open a .blend with bpy (Blender as a Python module) and export it with the add-on's code."""
    if not path.exists():
        raise FileNotFoundError(f"no such file: {path}")
    bpy = open_blend(path)
    from .export import export_scene
    from .light import saved_light_distance

    # a file without a camera is framed by the default camera, as a mesh file is (design.md, Defaults);
    # its light lit as the add-on lights it (its saved Light Distance, where set)
    distance = saved_light_distance(bpy.context.scene)
    return export_scene(bpy.context, scope="visible", require_camera=False, light_distance=distance)
