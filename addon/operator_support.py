"""What every bvhlab operator shares: turning exceptions and export warnings into reports, exporting
the scene, building a tree with a progress bar, and resolving output paths."""

from __future__ import annotations

import traceback
import warnings
from pathlib import Path

import bpy

from . import state


def run_reported(operator, context, work, quiet: tuple = ()) -> set[str]:
    """Run `work()` (returns the operator's result set). Export warnings, except those of the
    `quiet` classes, become WARNING reports; any exception becomes an ERROR report and
    {'CANCELLED'}: nothing escapes into Blender. The last message is kept for the panel."""
    from bvhlab.blender import ExportWarning

    key = state.key(context.scene)
    failure = None
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", ExportWarning)
        try:
            result = work()
        except Exception as error:  # every failure is reported, none raised (Blender conventions)
            result, failure = {"CANCELLED"}, _describe(error)
    for warning in caught:
        if not issubclass(warning.category, ExportWarning):  # not ours to report: show it as usual
            warnings.showwarning(warning.message, warning.category, warning.filename, warning.lineno)
        elif not issubclass(warning.category, quiet):
            operator.report({"WARNING"}, str(warning.message))
            state.messages[key] = ("WARNING", str(warning.message))
    if failure is not None:
        operator.report({"ERROR"}, failure)
        state.messages[key] = ("ERROR", failure)
    return result


def _describe(error: Exception) -> str:
    import bvhlab

    if isinstance(error, bvhlab.VulkanUnavailable):
        return f"No Vulkan: {error} (choose the CPU or Auto backend)"
    if isinstance(error, (ValueError, TypeError, RuntimeError, OSError)):
        return str(error)
    traceback.print_exc()  # a bug, not bad input: keep the trace in the console
    return f"bvhlab failed unexpectedly ({type(error).__name__}: {error}); see the system console"


def export_scene(context, require_camera: bool):
    """The scene as a bvhlab.Scene, over the panel's scope."""
    from bvhlab.blender import export_scene as export

    return export(
        context,
        scope=context.scene.bvhlab.scope,
        depsgraph=context.evaluated_depsgraph_get(),
        require_camera=require_camera,
    )


def build_tree(context, exported):
    """Build over `exported` with the panel's settings, showing progress in the window manager."""
    import bvhlab

    settings = context.scene.bvhlab
    window_manager = context.window_manager
    window_manager.progress_begin(0, 100)
    try:
        return bvhlab.build(
            exported,
            **settings.build_kwargs(),
            progress=lambda fraction: window_manager.progress_update(int(fraction * 100)) or True,
        )
    finally:
        window_manager.progress_end()


def remember_tree(context, bvh, exported, build_settings: dict | None = None) -> state.BuiltTree:
    """Cache the tree for the scene and keep the overlay's depth range inside its height.
    `build_settings`: what the tree was built with (BVHLAB_PG_settings.build_settings() taken when
    the build started; default: the settings now, for a build that ran at once)."""
    settings = context.scene.bvhlab
    if build_settings is None:
        build_settings = settings.build_settings()
    built = state.BuiltTree(bvh, exported, build_settings)
    state.trees[state.key(context.scene)] = built
    deepest = built.height - 1
    if settings.overlay_depth_max > deepest:
        settings.overlay_depth_max = deepest  # its update callback pulls min along
    if settings.overlay_depth_min > deepest:
        settings.overlay_depth_min = deepest
    from .overlay import tag_redraw

    tag_redraw()
    return built


def current_tree(context, exported) -> state.BuiltTree:
    """The cached tree when it was built with the current settings over the same geometry,
    otherwise a new one (cached)."""
    import numpy as np

    built = state.tree_for(context.scene)
    if (
        built is not None
        and built.settings == context.scene.bvhlab.build_settings()
        and np.array_equal(built.scene.triangles, exported.triangles)
        and np.array_equal(built.scene.spheres, exported.spheres)
    ):
        return built
    return remember_tree(context, build_tree(context, exported), exported)


def output_path(path: str, default_name: str) -> Path:
    """An absolute output path: '//' is the .blend's folder, or Blender's temporary folder while
    the file is unsaved; an empty path means '//<default_name>'."""
    path = path or "//" + default_name
    if path.startswith("//") and not bpy.data.filepath:
        return Path(bpy.app.tempdir or ".") / path[2:]
    return Path(bpy.path.abspath(path))
