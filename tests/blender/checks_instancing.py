"""Export, Build and F12 on scenes made of instances that live only while Blender's instance
iterator is on them (issue 39: geometry-nodes instances crashed or hung Blender on Build and F12,
nested collection instances hung it): a geometry-nodes scatter (Grid 50×50 → Instance on Points of
a 0.1 cube with a material) and 100 empties each instancing a collection of 100 cube instances.
The exported triangles (the instanced scene flattened: issue 34 keeps Blender's instancing as
instances of one mesh) are checked against the instance positions computed here from the node
settings and the empties (not by bvhlab), Build (two-level, as F12) against a direct build of the
instanced scene, and the F12 Depth pass (over Build's tree: no second build) against slab tests of
the cubes at those positions. The add-on must be enabled."""

from __future__ import annotations

from importlib import import_module

import bpy
import checks_engine
import harness
import numpy as np

import bvhlab
from bvhlab.blender import export_scene
from bvhlab.blender.compat import ensure_shader_tree

GRID_VERTICES, GRID_SIZE, CUBE_SIZE = 50, 10.0, 0.1
NESTED = 10  # 10 × 10 empties, each instancing 10 × 10 cubes
CUBE_TRIANGLES = 12


def _geometry_nodes_scatter(material):
    """A mesh object whose Geometry Nodes modifier outputs only instances: Grid → Instance on
    Points (Cube, Set Material) → Group Output."""
    tree = bpy.data.node_groups.new("Scatter", "GeometryNodeTree")
    tree.interface.new_socket("Geometry", in_out="OUTPUT", socket_type="NodeSocketGeometry")
    output = tree.nodes.new("NodeGroupOutput")
    grid = tree.nodes.new("GeometryNodeMeshGrid")
    grid.inputs["Size X"].default_value = grid.inputs["Size Y"].default_value = GRID_SIZE
    grid.inputs["Vertices X"].default_value = grid.inputs["Vertices Y"].default_value = GRID_VERTICES
    cube = tree.nodes.new("GeometryNodeMeshCube")
    cube.inputs["Size"].default_value = (CUBE_SIZE,) * 3
    paint = tree.nodes.new("GeometryNodeSetMaterial")
    paint.inputs["Material"].default_value = material
    instance = tree.nodes.new("GeometryNodeInstanceOnPoints")
    tree.links.new(cube.outputs["Mesh"], paint.inputs["Geometry"])
    tree.links.new(grid.outputs["Mesh"], instance.inputs["Points"])
    tree.links.new(paint.outputs["Geometry"], instance.inputs["Instance"])
    tree.links.new(instance.outputs["Instances"], output.inputs[0])
    obj = bpy.data.objects.new("Scatter", bpy.data.meshes.new("Scatter"))
    bpy.context.scene.collection.objects.link(obj)
    obj.modifiers.new("Scatter", "NODES").node_group = tree
    return obj


def _red_material():
    material = bpy.data.materials.new("Red")
    ensure_shader_tree(material)
    material.node_tree.nodes["Principled BSDF"].inputs["Base Color"].default_value = (0.9, 0.05, 0.05, 1.0)
    return material


def geometry_nodes_scene():
    scene = harness.empty_scene(resolution=(64, 48))
    _geometry_nodes_scatter(_red_material())
    harness.add_camera((0.0, -9.0, 7.0), (0.0, 0.0, 0.0), lens=30)
    harness.add_point_light((2.0, -3.0, 5.0))
    bpy.context.view_layer.update()
    grid = np.linspace(-GRID_SIZE / 2, GRID_SIZE / 2, GRID_VERTICES)
    centres = np.stack(np.meshgrid(grid, grid, [0.0], indexing="ij"), -1).reshape(-1, 3)
    return scene, centres


def nested_instances_scene():
    """Cube → collection "Leaf" instanced by 100 empties in collection "Row" (spacing 0.3) →
    instanced by 100 empties in the scene (spacing 4): 10,000 cubes, two levels of instancing."""
    scene = harness.empty_scene(resolution=(48, 36))
    leaf = bpy.data.collections.new("Leaf")
    cube = harness.add_box("Cube", (0.0, 0.0, 0.0), size=0.2)
    bpy.context.scene.collection.objects.unlink(cube)
    leaf.objects.link(cube)
    row = bpy.data.collections.new("Row")
    inner, outer = [], []
    for i in range(NESTED * NESTED):
        offset = (0.3 * (i % NESTED), 0.3 * (i // NESTED), 0.0)
        empty = bpy.data.objects.new(f"Leaf {i}", None)
        empty.instance_type, empty.instance_collection, empty.location = "COLLECTION", leaf, offset
        row.objects.link(empty)
        inner.append(offset)
    for i in range(NESTED * NESTED):
        offset = (4.0 * (i % NESTED) - 18.0, 4.0 * (i // NESTED) - 18.0, 0.0)
        empty = bpy.data.objects.new(f"Row {i}", None)
        empty.instance_type, empty.instance_collection, empty.location = "COLLECTION", row, offset
        bpy.context.scene.collection.objects.link(empty)
        outer.append(offset)
    harness.add_camera((0.0, -40.0, 30.0), (0.0, 0.0, 0.0), lens=30)
    harness.add_point_light((2.0, -3.0, 25.0))
    bpy.context.view_layer.update()
    centres = (np.array(outer)[:, None] + np.array(inner)[None]).reshape(-1, 3)
    return scene, centres


def _check_cubes(exported, centres: np.ndarray, half: float) -> None:
    """Every exported vertex is a corner of a cube at one of `centres`, and every cube is there."""
    assert len(exported.triangles) == len(centres) * CUBE_TRIANGLES, (len(exported.triangles), len(centres))
    vertices = exported.triangles.reshape(-1, 3).astype(np.float64)
    corners = centres[:, None] + half * np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)])
    expected = np.unique(np.round(corners.reshape(-1, 3), 4), axis=0)
    got = np.unique(np.round(vertices, 4), axis=0)
    assert got.shape == expected.shape and np.array_equal(got, expected), (got.shape, expected.shape)


def box_depth(camera, centres: np.ndarray, half: float, width: int, height: int) -> np.ndarray:
    """Planar depth of the nearest of the axis-aligned cubes (`centres`, half size `half`) through
    each pixel centre, by slab tests written here (not bvhlab's); MISS_DEPTH where none is hit.
    The rays' directions have a unit component along the view axis, so t is the planar depth."""
    directions = checks_engine._primary_directions(camera, width, height).astype(np.float64)
    origin = np.array(camera.position, np.float64)
    with np.errstate(divide="ignore", invalid="ignore"):
        inverse = 1.0 / directions
    best = np.full(len(directions), np.inf)
    for chunk in np.array_split(centres, max(1, len(centres) // 256)):
        lo = (chunk - half - origin)[None] * inverse[:, None]  # (rays, boxes, 3)
        hi = (chunk + half - origin)[None] * inverse[:, None]
        near = np.nan_to_num(np.minimum(lo, hi), nan=-np.inf).max(-1)
        far = np.nan_to_num(np.maximum(lo, hi), nan=np.inf).min(-1)
        hit = (near <= far) & (near > 0)
        best = np.minimum(best, np.where(hit, near, np.inf).min(1))
    best = best.reshape(height, width)
    return np.where(np.isfinite(best), best, checks_engine.MISS_DEPTH)


def _check_build_and_f12(tmp_dir, scene, exported, centres: np.ndarray, half: float) -> None:
    assert exported.is_instanced and len(exported.meshes) == 1, "the cube is not stored once"
    trees = import_module(harness.addon().__name__ + ".trees")
    builds = trees.counts.snapshot()[0]
    assert bpy.ops.bvhlab.build() == {"FINISHED"}
    built = harness.addon().state.tree_for(scene)
    direct = bvhlab.build(exported, config=scene.bvhlab.build_config())
    assert isinstance(built.bvh, bvhlab.InstancedBvh), "Build flattened the instances"
    assert built.bvh.stats["triangles_flattened"] == len(exported.flattened().triangles)
    assert built.bvh.stats["triangles"] == len(exported.triangles) + CUBE_TRIANGLES
    assert all(np.array_equal(a.nodes, b.nodes) for a, b in zip(built.bvh.meshes, direct.meshes))
    assert all(np.array_equal(a, b) for a, b in zip(built.bvh.tlas_boxes(), direct.tlas_boxes()))
    exported = exported.flattened()
    checks_engine.use_engine(scene, backend="cpu", render_supersampling=1, render_overlay=False, traversal="stack")
    passes = checks_engine.render_passes(tmp_dir)
    depth = passes["Depth"]
    # F12 renders the tree Build made: no second build (its instances may come in another order
    # from the render depsgraph: then only a new TLAS)
    assert trees.counts.snapshot()[0] == builds + 1
    assert checks_engine._last_final(scene)["tree"] in ("kept", "placed")
    width, height = scene.render.resolution_x, scene.render.resolution_y
    expected = box_depth(exported.camera, centres, half, width, height)
    hit = expected < checks_engine.MISS_DEPTH
    assert 0.05 < hit.mean() < 0.98, hit.mean()
    agree = np.where(hit, np.abs(depth - expected) <= 1e-4 * expected, depth == np.float32(checks_engine.MISS_DEPTH))
    assert agree.mean() >= 0.99, f"only {agree.mean():.4f} of the pixels have the cubes' depth"
    # the CPU tracer's wide traversal: through the TLAS's and the cube's 8-wide copies, the same image
    scene.bvhlab.traversal = "wide"
    wide = checks_engine.render_passes(tmp_dir, "wide")
    assert "wide walk" in checks_engine._last_final(scene)["device"]
    assert np.array_equal(wide["Combined"], passes["Combined"]) and np.array_equal(wide["Depth"], depth)
    scene.bvhlab.traversal = "stack"


def check_geometry_nodes_instances(tmp_dir) -> None:
    scene, centres = geometry_nodes_scene()
    exported = export_scene(bpy.context)
    flat = exported.flattened()
    _check_cubes(flat, centres, CUBE_SIZE / 2)
    red = [i for i, m in enumerate(flat.materials) if np.allclose(m.color, (0.9, 0.05, 0.05), atol=1e-3)]
    assert red and np.isin(flat.tri_material, red).all(), "the instances' Set Material is lost"
    _check_build_and_f12(tmp_dir, scene, exported, centres, CUBE_SIZE / 2)


def check_nested_collection_instances(tmp_dir) -> None:
    scene, centres = nested_instances_scene()
    exported = export_scene(bpy.context)
    _check_cubes(exported.flattened(), centres, 0.1)
    _check_build_and_f12(tmp_dir, scene, exported, centres, 0.1)
