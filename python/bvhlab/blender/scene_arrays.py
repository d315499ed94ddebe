"""A LiveScene sync's arrays (live.py `_arrays`): mesh 0, the items placed in the world, and the
instances of the shared meshes."""

from __future__ import annotations

import numpy as np

from ..scene import Scene
from .instancing import Layout, SharedMesh, instance_transforms, transforms_again
from .material_table import map_slots
from .sphere import place_sphere


def mesh_zero(items: dict, layout: Layout) -> tuple[list, list, list, list, dict]:
    """(material index arrays, world triangles, spheres, sphere materials, each sphere's row by its
    item's key) of the items placed in mesh 0, in walk order; each item placed once while neither
    its mesh nor matrix changes. A sphere scaled to nothing has no row."""
    triangles: list = []
    tri_material: list = []
    spheres: list = []
    sphere_material: list = []
    sphere_rows: dict[tuple, int] = {}
    for key, item in items.items():
        if layout.mesh_of[key] or item.slot_table is None:
            continue
        if item.mesh is None:
            assert item.bounds is not None  # a sphere keeps its object-space bounds
            if item.placed is None:
                item.placed = place_sphere(item.bounds, item.matrix, item.name)
            if item.placed.size:  # none where scaled to nothing
                sphere_rows[key] = len(spheres)
                spheres.append(item.placed)
                sphere_material.append(item.slot_table[0])
        else:
            if item.placed is None:
                item.placed = item.mesh.world_triangles(item.matrix, item.name)
            triangles.append(item.placed)
            tri_material.append(map_slots(item.slot_table, item.mesh.slots))
    return tri_material, triangles, spheres, sphere_material, sphere_rows


def instances(
    previous: Scene | None,
    world: np.ndarray,
    layout: Layout,
    shared: list[SharedMesh],
    arrays: dict,
    report,
    changed: np.ndarray | None = None,
) -> tuple:
    """(instance_mesh, instance_transforms): mesh 0 once where it was modelled (when it has
    primitives), then the shared meshes' instances; (None, None) without shared meshes; the
    `previous` sync's where the geometry did not change. `changed`: the rows of the only items
    that moved or changed their meshes, in the `previous` sync's layout and mesh 0 (placed_only.py):
    the previous transforms with theirs made again."""
    if not shared:
        return None, None
    if previous is not None and not report.geometry and previous.instance_transforms is not None:
        return previous.instance_mesh, previous.instance_transforms
    if changed is not None and previous is not None and previous.instance_transforms is not None:
        return previous.instance_mesh, transforms_again(previous.instance_transforms, layout, world, shared, changed)
    mesh_of, transforms = instance_transforms(layout, world, shared)
    if len(arrays["triangles"]) or len(arrays["spheres"]):
        identity = np.eye(4, dtype=np.float32)[None, :3]
        mesh_of, transforms = (
            np.concatenate([[0], mesh_of]).astype(np.int32),
            np.concatenate([identity, transforms]),
        )
    return mesh_of, np.ascontiguousarray(transforms)
