"""Blender's own panels the engine shows (their COMPAT_ENGINES get the engine's id while the add-on
is enabled). Pure bpy: registration imports no bvhlab. The names are the same from 4.2 to 5.2
(checked under bpy 4.2, 5.2 and Blender 4.3)."""

from __future__ import annotations

import bpy

#: EEVEE's material and world surface panels: the engine reads the same shader nodes.
SHADING_PANELS = ("EEVEE_MATERIAL_PT_context_material", "EEVEE_MATERIAL_PT_surface", "EEVEE_WORLD_PT_surface")
#: Generic panels that make no sense for an engine with its own pass panel.
EXCLUDED_PANELS = ("VIEWLAYER_PT_filter", "VIEWLAYER_PT_layer_passes")


def engine_panels() -> list:
    """Blender's generic panels, those that list the pseudo-engine 'BLENDER_RENDER' (output, format,
    frame range, colour management, camera and light data, ...), and the shading panels."""
    panels, stack = [], list(bpy.types.Panel.__subclasses__())
    while stack:
        panel = stack.pop()
        stack.extend(panel.__subclasses__())
        engines = getattr(panel, "COMPAT_ENGINES", None)
        if not isinstance(engines, set) or panel.__name__ in EXCLUDED_PANELS:
            continue
        if "BLENDER_RENDER" in engines or panel.__name__ in SHADING_PANELS:
            panels.append(panel)
    return panels
