"""The world colour → the atmosphere colour (`Scene.sky`) that misses see (report §2.1)."""

from __future__ import annotations

import warnings

from ..scene import DEFAULT_SKY
from ..scene_checks import FIELD_CHECKS
from .compat import shader_tree
from .errors import ExportWarning, naming


def gather_sky(scene, depsgraph=None) -> tuple[float, float, float]:
    """_sky's colour, checked as a Scene checks its sky, its errors naming the world (ExportError)."""
    sky = _sky(scene, depsgraph)
    if scene.world is not None:
        with naming("world", scene.world.name):
            FIELD_CHECKS["sky"](None, sky)
    return sky


def _sky(scene, depsgraph=None) -> tuple[float, float, float]:
    """Colour × strength of the world's Background node when it is a plain colour; the world's
    viewport colour when the background is a texture (with an ExportWarning); bvhlab's default
    sky when the scene has no world. With `depsgraph`, the evaluated world's (its animation at the
    depsgraph's frame: the original's values are whatever was last written to it)."""
    world = scene.world
    if world is None:
        return DEFAULT_SKY
    if depsgraph is not None:
        world = world.evaluated_get(depsgraph)
    background = _background_node(world)
    if background is None:
        return tuple(world.color)
    color, strength = background.inputs["Color"], background.inputs["Strength"]
    if color.is_linked or strength.is_linked:
        warnings.warn(
            f"world '{world.name}': the background is not a plain colour; using the world's viewport colour",
            ExportWarning,
            stacklevel=2,
        )
        return tuple(world.color)
    return tuple(max(c, 0.0) * strength.default_value for c in color.default_value[:3])


def _background_node(world):
    tree = shader_tree(world)
    output = tree.get_output_node("ALL") if tree is not None else None
    surface = output.inputs.get("Surface") if output is not None else None
    if surface is None or not surface.is_linked:
        return None
    node = surface.links[0].from_node
    return node if node.bl_idname == "ShaderNodeBackground" else None
