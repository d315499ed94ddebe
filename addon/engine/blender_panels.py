"""Blender's own panels the engine shows (their COMPAT_ENGINES get the engine's id while the add-on
is enabled): those of what its renders follow. Pure bpy: registration imports no bvhlab. The names
are the same from 4.2 to 5.2 (checked under bpy 4.2, 5.2 and Blender 4.3)."""

from __future__ import annotations

import bpy

#: EEVEE's material and world surface panels: the engine reads the same shader nodes.
SHADING_PANELS = ("EEVEE_MATERIAL_PT_context_material", "EEVEE_MATERIAL_PT_surface", "EEVEE_WORLD_PT_surface")
#: Generic panels that make no sense for an engine with its own pass panel.
EXCLUDED_PANELS = ("VIEWLAYER_PT_filter", "VIEWLAYER_PT_layer_passes")
#: Panels of what the engine does not render: none now (stereoscopy and multi-view render each
#: view). Freestyle and Grease Pencil keep theirs: Blender draws both over the engine's image
#: (Freestyle through EEVEE); measured under bpy 4.2 and 5.2 (tests/blender/checks_addon.py
#: check_engine_panels_follow_the_renders).
UNSUPPORTED_PANELS: tuple[str, ...] = ()


def engine_panels() -> list:
    """Blender's generic panels, those that list the pseudo-engine 'BLENDER_RENDER' (output, format,
    frame range, colour management, camera and light data, ...), but those of what the engine does
    not render; and the shading panels."""
    panels, stack = [], list(bpy.types.Panel.__subclasses__())
    while stack:
        panel = stack.pop()
        stack.extend(panel.__subclasses__())
        engines = getattr(panel, "COMPAT_ENGINES", None)
        if not isinstance(engines, set) or panel.__name__ in EXCLUDED_PANELS + UNSUPPORTED_PANELS:
            continue
        if "BLENDER_RENDER" in engines or panel.__name__ in SHADING_PANELS:
            panels.append(panel)
    return panels
