"""Holdouts as Cycles renders them: an object's Holdout (Object ▸ Visibility), a view layer's
holdout collection, the Holdout shader, and an instancer's holdout (Cycles decides an instance's by
the object instancing it: a holdout object inside an instanced collection is not one). Where a
camera ray meets a holdout the pixel has no colour and no alpha and the sky's depth, on an opaque
film and a transparent one. Checked pixel by pixel against Cycles' Combined alpha and Depth pass
(1 sample through the pixel centre, checks_cameras.use_cycles_reference), on the CPU reference and
on Vulkan. Before, every holdout was rendered as a surface (a note said so)."""

from __future__ import annotations

import bpy
import harness
import numpy as np
from checks_cameras import MISS_DEPTH, camera_scene, interior, use_cycles_reference, use_engine, vulkan_backends
from checks_engine import _last_final, render_passes

from bvhlab.blender.compat import ensure_shader_tree

#: Pixels whose alpha may differ from Cycles': a ray grazing a holdout's edge (the interior of the
#: image, checks_cameras.interior, must agree on all).
EDGE_SHARE = 0.02


def holdout_scene():
    """camera_scene with a holdout of each kind: Box A (the object's flag), a box in a holdout
    collection, Box B's material a Holdout shader, the crate instanced by 'Crate 1' (the
    instancer's flag); and Crate part 0 flagged inside the crate, which Cycles ignores."""
    scene = camera_scene((80, 60))
    bpy.data.objects["Box A"].is_holdout = True
    held = bpy.data.collections.new("Held")
    scene.collection.children.link(held)
    box = harness.add_box("Held box", (-0.2, -2.5, 0.4), size=0.6)
    scene.collection.objects.unlink(box)
    held.objects.link(box)
    bpy.context.view_layer.layer_collection.children["Held"].holdout = True
    material = bpy.data.materials.new("Hole")
    tree = ensure_shader_tree(material)
    tree.nodes.clear()
    output, hole = tree.nodes.new("ShaderNodeOutputMaterial"), tree.nodes.new("ShaderNodeHoldout")
    tree.links.new(hole.outputs[0], output.inputs["Surface"])
    bpy.data.objects["Box B"].data = bpy.data.objects["Box B"].data.copy()  # the crate keeps its own
    bpy.data.objects["Box B"].data.materials.append(material)
    bpy.data.objects["Crate 1"].is_holdout = True
    bpy.data.objects["Crate part 0"].is_holdout = True  # instanced: Cycles decides by 'Crate 0'
    bpy.context.view_layer.update()
    return scene


def alpha_and_depth(tmp_dir, name: str) -> tuple[np.ndarray, np.ndarray]:
    passes = render_passes(tmp_dir, name)
    return passes["Combined"][..., 3], passes["Depth"]


def check_holdouts_against_cycles(tmp_dir) -> None:
    scene = holdout_scene()
    for film in (False, True):
        scene.render.film_transparent = film
        use_cycles_reference(scene)
        alpha_cycles, depth_cycles = alpha_and_depth(tmp_dir, f"cycles_{film}")
        hole = (alpha_cycles == 0) & (depth_cycles >= MISS_DEPTH * 0.5)
        if not film:  # every hole a holdout makes; on an opaque film nothing else is one
            assert hole.sum() > 150, hole.sum()
        for backend in vulkan_backends():
            use_engine(scene, backend)
            alpha, depth = alpha_and_depth(tmp_dir, f"{backend}_{film}")
            assert not _last_final(scene)["unrendered"], _last_final(scene)["unrendered"]
            same, _ = interior(depth_cycles)
            differ = alpha != alpha_cycles
            line = (
                f"film_transparent {film}, {backend}: {int(hole.sum())} holes in Cycles' image; alpha differs on "
                f"{differ.mean():.4f} of the pixels, {differ[same].sum()} of {same.sum()} interior"
            )
            print(line)
            assert differ.mean() <= EDGE_SHARE and not differ[same].any(), line
            agree = ~differ & (alpha == 0)
            assert np.all(depth[agree] == depth_cycles[agree]), line  # the sky's depth, 1e10
