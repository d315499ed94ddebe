"""Blender scene → `bvhlab.Scene` (the only part of bvhlab, beside the add-on, that imports `bpy`).

    from bvhlab.blender import export_scene, export_scene_file
    scene = export_scene(bpy.context, scope="visible")      # a bvhlab.Scene
    export_scene_file("scene.npz", bpy.context)             # the file the CLI reads
    live = LiveScene(); live.sync(depsgraph)                # kept between frames (render engine)

One small module per kind of Blender data (glTF-Blender-IO style): `scope` picks the objects,
`mesh`, `sphere`, `material`, `camera`, `light` and `world` each gather one thing, `live` puts
them together and keeps them between frames (reading again what `depsgraph_updates` names and
saying what changed in a `sync_report`), `export` is one sync of a new LiveScene. `compat`
holds what differs between the supported Blender versions (4.2 LTS to 5.3); nothing else checks
`bpy.app.version`.
"""

from .load import bpy_module

bpy_module()  # first: a clear error where bpy is missing, a Ctrl-C while it loads held back
from .errors import EmptySceneWarning, ExportError, ExportWarning, SubstituteWarning  # noqa: E402
from .export import export_scene, export_scene_file  # noqa: E402
from .light import intensity_from_watts  # noqa: E402
from .live import LiveScene  # noqa: E402
from .scope import SCOPES  # noqa: E402
from .sphere import SPHERE_PROPERTY, is_analytic_sphere  # noqa: E402
from .sync_report import SyncReport  # noqa: E402

__all__ = [
    "export_scene",
    "export_scene_file",
    "LiveScene",
    "SyncReport",
    "ExportError",
    "ExportWarning",
    "SubstituteWarning",
    "EmptySceneWarning",
    "SCOPES",
    "SPHERE_PROPERTY",
    "is_analytic_sphere",
    "intensity_from_watts",
]
