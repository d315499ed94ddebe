"""Blender material → `bvhlab.Material` (report §2.1: colour, reflective, transparent, IOR)."""

from __future__ import annotations

import warnings

import numpy as np

from ..scene import Material
from .compat import shader_tree
from .errors import ExportWarning, naming


def gather_material(material) -> Material:
    """_gather's Whitted material, its errors naming the material (ExportError)."""
    if material is None:
        return Material()
    with naming("material", material.name):
        return _gather(material)


def _gather(material) -> Material:
    """Read the shader that feeds the material's output: Principled BSDF gives base colour,
    metallic → reflective, transmission weight → transparent, IOR; Diffuse, Glossy, Glass,
    Refraction and Emission map to the obvious Whitted material, Holdout to a holdout. Anything else falls back to the
    viewport display colour and metallic, with an ExportWarning. `None` (an empty slot) is matte grey."""
    if shader_tree(material) is None:  # no nodes (4.x): Blender renders the viewport colour
        return _material(material.diffuse_color[:3], reflective=material.metallic)
    shader = _surface_shader(material)
    reader = _READERS.get(shader.bl_idname) if shader is not None else None
    if reader is None:
        what = f"a '{shader.name}' node" if shader is not None else "no shader node"
        warnings.warn(
            f"material '{material.name}' uses {what}; using its viewport display colour and metallic",
            ExportWarning,
            stacklevel=2,
        )
        return _material(material.diffuse_color[:3], reflective=material.metallic)
    return reader(shader, material)


def _surface_shader(material):
    tree = shader_tree(material)
    output = tree.get_output_node("ALL") or tree.get_output_node("CYCLES") or tree.get_output_node("EEVEE")
    surface = output.inputs.get("Surface") if output is not None else None
    if surface is None or not surface.is_linked:
        return None
    return surface.links[0].from_node


def _input(node, name: str, material, fallback):
    """A socket's value: its own when unlinked, an RGB or Value node's output when linked to one;
    otherwise `fallback` (textures cannot be one colour) with a warning."""
    socket = node.inputs.get(name)
    if socket is None:
        return fallback
    if not socket.is_linked:
        return socket.default_value
    source = socket.links[0].from_node
    if source.bl_idname in ("ShaderNodeRGB", "ShaderNodeValue"):
        return source.outputs[0].default_value
    warnings.warn(
        f"material '{material.name}': '{name}' comes from a '{source.name}' node; "
        f"using the viewport display value instead",
        ExportWarning,
        stacklevel=3,
    )
    return fallback


def _material(color, reflective=0.0, transparent=0.0, ior=1.5) -> Material:
    color = np.clip(np.asarray(color[:3], np.float64), 0.0, None)
    return Material(
        tuple(color),
        float(np.clip(reflective, 0, 1)),
        float(np.clip(transparent, 0, 1)),
        float(ior) if ior > 0 else 1.5,
    )


def _principled(node, material) -> Material:
    # the Principled BSDF lays the metal over the dielectric base, whose transmission is the rest's:
    # metallic 1 with transmission 1 is a mirror (it was reflective 1 and transparent 1, twice the
    # light arriving)
    metallic = float(np.clip(_input(node, "Metallic", material, material.metallic), 0, 1))
    transmission = float(np.clip(_input(node, "Transmission Weight", material, 0.0), 0, 1))
    return _material(
        _input(node, "Base Color", material, material.diffuse_color),
        reflective=metallic,
        transparent=transmission * (1.0 - metallic),
        ior=_input(node, "IOR", material, 1.5),
    )


def _diffuse(node, material) -> Material:
    return _material(_input(node, "Color", material, material.diffuse_color))


def _glossy(node, material) -> Material:
    return _material(_input(node, "Color", material, material.diffuse_color), reflective=1.0)


def _glass(node, material) -> Material:
    return _material(
        _input(node, "Color", material, material.diffuse_color), transparent=1.0, ior=_input(node, "IOR", material, 1.5)
    )


def _holdout(node, material) -> Material:
    # Cycles' Holdout shader: a hole in the image (alpha 0), black to other rays (Material.holdout)
    return Material((0.0, 0.0, 0.0), holdout=True)


_READERS = {
    "ShaderNodeBsdfPrincipled": _principled,
    "ShaderNodeBsdfDiffuse": _diffuse,
    "ShaderNodeEmission": _diffuse,
    "ShaderNodeBsdfGlossy": _glossy,
    "ShaderNodeBsdfAnisotropic": _glossy,
    "ShaderNodeBsdfGlass": _glass,
    "ShaderNodeBsdfRefraction": _glass,
    "ShaderNodeHoldout": _holdout,
}
