"""Reading a `.blend` file outside Blender: open it with bpy (Blender as a Python module) and export
it with the same code the add-on uses."""

from __future__ import annotations

import os
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
        raise SceneFileError(f"{path} cannot be read as a .blend file: {reason}") from None
    finally:
        sys.stdout.flush()
        os.dup2(saved, 1)
        os.close(saved)
    return bpy


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
