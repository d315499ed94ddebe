"""A sample of the exported primitives' centres in the world, for calibrating a light
(`light.gather_light`) without reading every triangle."""

from __future__ import annotations

import numpy as np

from .mesh import MeshData


def primitive_sample(items: dict, world: np.ndarray, spheres: np.ndarray, size: int = 4096) -> np.ndarray:
    """Centres of about `size` primitives, as float64 (N,3): every k-th triangle of the world
    triangles in walk order (the flat export's order; instances placed where they are, so an
    instanced export samples the same triangles as the flat one) and every k-th sphere. `world`:
    the items' matrices (row i the i-th item's)."""
    parts = [spheres[:: max(1, len(spheres) // size), :3].astype(np.float64)]
    meshes: list[MeshData] = []
    index: dict[int, int] = {}  # id of a mesh → its place in `meshes`
    rows, mesh_of = [], []  # the items with triangles: their row and mesh
    for row, item in enumerate(items.values()):
        mesh = item.mesh
        if mesh is not None and item.slot_table is not None:
            k = index.get(id(mesh))
            if k is None:
                k = index[id(mesh)] = len(meshes)
                meshes.append(mesh)
            rows.append(row)
            mesh_of.append(k)
    sizes = np.array([mesh.triangle_count for mesh in meshes], np.int64)
    blocks = np.array(mesh_of, np.int64)
    keep = sizes[blocks] > 0 if len(blocks) else np.zeros(0, bool)
    blocks, rows = blocks[keep], np.array(rows, np.int64)[keep]
    if len(blocks):
        counts = sizes[blocks]
        stride = max(1, int(counts.sum()) // size)
        offsets = np.cumsum(counts) - counts
        first = (-offsets) % stride
        picks = np.maximum(0, (counts - first + stride - 1) // stride)
        which = np.repeat(np.arange(len(blocks)), picks)
        local = first[which] + (np.arange(len(which)) - np.repeat(np.cumsum(picks) - picks, picks)) * stride
        matrices = world[rows[which]]
        centres = np.empty((len(which), 3))
        for m, mesh in enumerate(meshes):
            chosen = np.flatnonzero(blocks[which] == m)
            corners = mesh.corners.reshape(-1, 3)[local[chosen]]
            centres[chosen] = mesh.positions[corners].astype(np.float64).mean(1)
        placed = np.einsum("nij,nj->ni", matrices[:, :3, :3], centres) + matrices[:, :3, 3]
        parts.insert(0, placed)
    return np.concatenate(parts)
