"""Differences between the Blender versions bvhlab supports (4.2 LTS to 5.3), in one place.

- Node trees: in 4.x a material or world made by a script has no node tree until `use_nodes` is
  set, and one with `use_nodes` off renders its viewport colour; 5.0 always uses nodes and
  deprecates `use_nodes` (removed in 6.0). `shader_tree` and `ensure_shader_tree` hide both.
- The sidebar's tab: `Region.active_panel_category` is writable only in newer versions;
  `show_sidebar_tab` says whether it could switch.
- `gpu` buffers: `np.asarray` of a multi-dimensional `gpu.types.Buffer` reads back scrambled in
  5.0; `buffer_to_array` flattens first, which every version reads correctly.
- `gpu` builtin shaders: the `3D_` prefixes of 3.x are gone (4.0+): `builtin_shader` takes the
  unprefixed name everywhere.
- Multilayer OpenEXR output: from 5.0 a media type must be chosen before the file format:
  `use_multilayer_exr`.
- A scene camera that is not a camera (an empty, a light other than a spot): Cycles gives it a
  50 mm lens up to 5.0 and Blender's 35 mm in 5.3 (measured against a camera of each lens); 5.1
  and 5.2's Cycles crash rendering through one (a segfault), their Workbench and EEVEE take 35 mm
  as Blender's other engines always have: `NON_CAMERA_LENS_MM`.
Mesh attributes (`attributes["position"]`, `loop_triangle_polygons`, `material_index`) and the
Principled BSDF socket names ("Transmission Weight") are the same from 4.2 on.
"""

from __future__ import annotations

import bpy
import numpy as np

#: 5.0 and later: materials and worlds always render with their node tree (reading `use_nodes`
#: there only raises a DeprecationWarning).
ALWAYS_NODES = bpy.app.version >= (5, 0, 0)

#: The focal length (mm) Cycles renders a scene camera with that is not a camera (camera.StandInLens).
NON_CAMERA_LENS_MM = 35.0 if bpy.app.version >= (5, 1, 0) else 50.0


def shader_tree(id_data):
    """The node tree a material or world renders with, or None when it renders without nodes."""
    if not ALWAYS_NODES and not id_data.use_nodes:
        return None
    return id_data.node_tree


def ensure_shader_tree(id_data):
    """The node tree of a material or world, created with Blender's default nodes (Principled
    BSDF, Background) if the id has none yet (4.x); 5.x creates it with the id."""
    if not ALWAYS_NODES and (id_data.node_tree is None or not id_data.use_nodes):
        id_data.use_nodes = True
    return id_data.node_tree


def show_sidebar_tab(region, category: str) -> bool:
    """Switch a sidebar region to the tab `category`; False where the version cannot."""
    try:
        region.active_panel_category = category
    except (AttributeError, TypeError):
        return False
    return region.active_panel_category == category


def buffer_to_array(buffer, width: int, height: int, channels: int = 4) -> np.ndarray:
    """A `gpu.types.Buffer` of width×height pixels → float32 (height, width, channels), row 0 at
    the bottom."""
    buffer.dimensions = width * height * channels
    return np.asarray(buffer, np.float32).reshape(height, width, channels)


def builtin_shader(name: str):
    """`gpu.shader.from_builtin` by its 4.0+ name (e.g. "UNIFORM_COLOR", "POLYLINE_UNIFORM_COLOR")."""
    import gpu

    return gpu.shader.from_builtin(name)


def use_multilayer_exr(image_settings) -> None:
    """Make `image_settings` (ImageFormatSettings) write a multilayer OpenEXR, every pass of every
    view layer: file format 'OPEN_EXR_MULTILAYER'; from 5.0 the media type 'MULTI_LAYER_IMAGE'
    must be chosen first (it leaves that format the only one)."""
    if "media_type" in image_settings.bl_rna.properties:
        image_settings.media_type = "MULTI_LAYER_IMAGE"
    image_settings.file_format = "OPEN_EXR_MULTILAYER"


def action_data_paths(action) -> set[str]:
    """The data paths an Action's F-curves animate. 4.4 brought layered ("slotted") actions, whose
    F-curves live in channel bags of layers' strips, and 5.0 removed `Action.fcurves` (the legacy
    list 4.2 has); every slot's curves are taken (more, never fewer, than the object's own)."""
    if action is None:
        return set()
    paths: set[str] = set()
    for layer in getattr(action, "layers", ()):
        for strip in layer.strips:
            for bag in getattr(strip, "channelbags", ()):
                paths.update(curve.data_path for curve in bag.fcurves)
    legacy = getattr(action, "fcurves", None)
    if legacy is not None:
        paths.update(curve.data_path for curve in legacy)
    return paths
