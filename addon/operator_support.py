"""What every bvhlab operator shares: turning exceptions and export warnings into reports, exporting
the scene, building a tree with a progress bar, and resolving output paths."""

from __future__ import annotations

import traceback
import warnings
from contextlib import contextmanager
from pathlib import Path

import bpy

from . import state
from .trees import TreeKey, cache, key_of


def run_reported(operator, context, work, quiet: tuple = (), scene_key: int | None = None) -> set[str]:
    """Run `work()` (returns the operator's result set). Export warnings, except those of the
    `quiet` classes, become WARNING reports; any exception becomes an ERROR report and
    {'CANCELLED'}: nothing escapes into Blender. The last message is kept for the panel of the
    scene `scene_key` names (default: the context's; a build ending after the window switched
    scene reports to the scene it built for)."""
    from bvhlab.blender import ExportWarning

    key = state.key(context.scene) if scene_key is None else scene_key
    failure = None
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", ExportWarning)
        try:
            result = work()
        except Exception as error:  # every failure is reported, none raised (Blender conventions)
            result, failure = {"CANCELLED"}, describe_error(error)
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


def describe_error(error: Exception) -> str:
    """What an operator (or F12) reports of an exception: bad input's own message; a bug's type and
    message, its traceback printed to the console."""
    import bvhlab

    if isinstance(error, bvhlab.VulkanUnavailable):
        return f"No Vulkan: {error} (choose the CPU or Auto backend)"
    if isinstance(error, (ValueError, TypeError, RuntimeError, OSError)):
        return str(error)
    traceback.print_exc()  # a bug, not bad input: keep the trace in the console
    return f"bvhlab failed unexpectedly ({type(error).__name__}: {error}); see the system console"


def export_scene(context, require_camera: bool):
    """The scene as a bvhlab.Scene, over the panel's scope: Blender's instancing as meshes and
    instances (issue 34), which the sidebar's Build, Render, Export stats and Compare build as a
    two-level tree, as F12 and the viewport do (the one cache of trees, trees.py)."""
    from bvhlab.blender import export_scene as export

    from .engine.settings import fixed_light_distance

    return export(
        context,
        scope=context.scene.bvhlab.scope,
        depsgraph=context.evaluated_depsgraph_get(),
        require_camera=require_camera,
        light_distance=fixed_light_distance(context.scene),
    )


@contextmanager
def window_progress(context):
    """A build's progress callable, drawing in the window manager's progress cursor while inside."""
    window_manager = context.window_manager
    window_manager.progress_begin(0, 100)
    try:
        yield lambda fraction: window_manager.progress_update(int(fraction * 100)) or True
    finally:
        window_manager.progress_end()


def remember_tree(context, key: TreeKey, scene=None) -> state.BuiltTree:
    """Make the cache's tree of `key` (with the scene it was made over: trees.SceneTree.scene) the
    one the sidebar of `scene` (default: the context's) shows, and keep the overlay's depth range
    inside its height."""
    from . import follow

    scene = context.scene if scene is None else scene
    built = state.BuiltTree(key, cache.tree(key))
    state.trees[state.key(scene)] = built
    follow.tree_made(state.key(scene), built)
    settings = scene.bvhlab
    deepest = built.height - 1
    if settings.overlay_depth_max > deepest:
        settings.overlay_depth_max = deepest  # its update callback pulls min along
    if settings.overlay_depth_min > deepest:
        settings.overlay_depth_min = deepest
    from .overlay import tag_redraw

    tag_redraw()
    return built


def current_tree(context, exported):
    """The Bvh of the cache's tree for the scene's settings, made to fit `exported` (kept when it
    fits already: built by Build, F12 or the viewport before), with a progress bar while it
    builds; the sidebar shows it from now on."""
    key = key_of(context.scene)
    with window_progress(context) as progress:
        update = cache.tree(key).update(exported, progress=progress)
    remember_tree(context, key)
    return update.bvh


def output_path(path: str, default_name: str) -> Path:
    """An absolute output path: '//' is the .blend's folder, or Blender's temporary folder while
    the file is unsaved (temporary_note says so); an empty path means '//<default_name>'."""
    path = path or "//" + default_name
    if path.startswith("//") and not bpy.data.filepath:
        return Path(bpy.app.tempdir or ".") / path[2:]
    return Path(bpy.path.abspath(path))


def named_output_path(path: str, default_name: str) -> Path:
    """output_path, with the default name's suffix added to a name without one (the file browser's
    convention); a folder, or a name that is the suffix alone (".json": no stem), kept as it is for
    the writer's check to refuse."""
    out = output_path(path, default_name)
    suffix = Path(default_name).suffix
    if not out.suffix and not out.is_dir() and out.name.lower() != suffix:
        out = out.with_name(out.name + suffix)
    return out


def temporary_note(path: Path) -> str:
    """What a report adds for a file written into Blender's temporary folder, which Blender deletes
    when it quits (an unsaved file's '//': the report named the file as if it stayed)."""
    temporary = bpy.app.tempdir
    if temporary and Path(path).resolve().is_relative_to(Path(temporary).resolve()):
        return " (Blender's temporary folder, deleted when Blender quits: save the .blend to write beside it)"
    return ""
