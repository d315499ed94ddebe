"""bvhlab for Blender: build bounding volume hierarchies over the scene with the split methods of
Sandén's report, draw their boxes by depth in the viewport, ray trace with bvhlab's Whitted
tracer, export statistics and compare methods (View3D ▸ Sidebar ▸ BVH); and the render engine
"bvhlab Whitted" (Render Properties ▸ Render Engine) for F12, the command line and the viewport's
Rendered shading (engine/).

Everything the panel does is an operator (bvhlab.build, bvhlab.render, bvhlab.export_stats,
bvhlab.compare, bvhlab.pick_box), so scripts drive the same code as the buttons. The compiled core comes from the
bundled bvhlab wheel; registering reads the core's names, defaults and limits from it (~25 ms),
the rest is imported when an operator runs.
"""

from __future__ import annotations

import sys

import bpy
from bpy.app.handlers import persistent

from . import background, engine, follow, legend_icons, ops_costs, ops_counters, ops_inspect, overlay, state
from .ops_build import BVHLAB_OT_build
from .ops_compare import BVHLAB_OT_compare
from .ops_export_stats import BVHLAB_OT_export_stats
from .ops_fresh_sah import BVHLAB_OT_fresh_sah
from .ops_render import BVHLAB_OT_render
from .panels import (
    BVHLAB_PT_compare,
    BVHLAB_PT_cost,
    BVHLAB_PT_export,
    BVHLAB_PT_inspect,
    BVHLAB_PT_main,
    BVHLAB_PT_object,
    BVHLAB_PT_overlay,
    BVHLAB_PT_render,
)
from .properties import BVHLAB_PG_settings, register_properties, unregister_properties

classes = (
    BVHLAB_PG_settings,
    BVHLAB_OT_build,
    BVHLAB_OT_render,
    BVHLAB_OT_export_stats,
    BVHLAB_OT_fresh_sah,
    BVHLAB_OT_compare,
    *ops_inspect.classes,
    *ops_costs.classes,
    BVHLAB_PT_main,
    BVHLAB_PT_overlay,
    BVHLAB_PT_inspect,
    BVHLAB_PT_cost,
    BVHLAB_PT_render,
    *ops_counters.classes,
    BVHLAB_PT_compare,
    BVHLAB_PT_export,
    BVHLAB_PT_object,
)
_register_classes, _unregister_classes = bpy.utils.register_classes_factory(classes)


@persistent
def _forget_trees(*_args) -> None:
    """Trees belong to the scenes of the open file: drop them when another file loads, and stop
    the builds and comparisons running for it (their results would land on the new file's scene)."""
    background.stop_all()
    state.clear()
    engine.forget()
    follow.forget()


def register() -> None:
    from pathlib import Path

    from .core_check import core_mismatch

    state.core_warning = core_mismatch(Path(__file__).parent)
    if state.core_warning:
        print(f"bvhlab: {state.core_warning}", file=sys.stderr)
    _register_classes()
    register_properties()
    engine.register()
    bpy.app.handlers.load_pre.append(_forget_trees)
    overlay.add_handler()
    follow.register()


def unregister() -> None:
    background.stop_all()  # before the settings they read go away with unregister_properties
    overlay.remove_handler()
    follow.unregister()
    if _forget_trees in bpy.app.handlers.load_pre:
        bpy.app.handlers.load_pre.remove(_forget_trees)
    engine.unregister()
    unregister_properties()
    _unregister_classes()
    legend_icons.unregister()
    state.clear()
