"""The statistics of a two-level tree (issue 34) as a whole: what `InstancedBvh.stats` adds to the
core's TLAS numbers, so the add-on's panel, Export stats, `bvhlab build --json` and Compare report
an instanced scene's TLAS and BLASes instead of flattening it."""

from __future__ import annotations

import numpy as np

#: Per-mesh lists in InstancedBvh.stats (index: the mesh), written one value per row by stats_files.
MESH_METRICS = (
    "mesh_primitives",
    "mesh_instances",
    "mesh_nodes",
    "mesh_height",
    "mesh_sah_cost",
    "mesh_memory_bytes",
)


def box_areas(lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """Surface area of each box (float64); 0 for an empty box (lo > hi)."""
    e = np.maximum(hi.astype(np.float64) - lo.astype(np.float64), 0.0)
    return 2.0 * (e[:, 0] * e[:, 1] + e[:, 1] * e[:, 2] + e[:, 2] * e[:, 0])


def two_level_sah_cost(tlas_sah: float, lo: np.ndarray, hi: np.ndarray, mesh_of, mesh_sah) -> float:
    """The SAH cost of a two-level tree (C_trav = C_isect = 1, the formula of `Bvh.stats`): the
    TLAS's cost with each instance leaf's one primitive replaced by its BLAS's expected cost. The
    TLAS (one instance per leaf, default_tlas_config) counts A(leaf)/A(root)·1 for a leaf; reaching
    instance i costs A(box_i)/A(root) and walking its BLAS then costs mesh_sah[mesh_of[i]] (a BLAS's
    SAH is relative to its own root box, which is the instance's box moved into its space: exact
    for translations, the usual estimate otherwise; MacDonald and Booth 1990). One identity
    instance gives its tree's own SAH cost exactly."""
    areas = box_areas(lo, hi)
    present = areas > 0
    if not present.any():
        return float(tlas_sah)
    root_lo, root_hi = lo[present].min(0), hi[present].max(0)
    root = float(box_areas(root_lo[None], root_hi[None])[0])
    if root <= 0:
        return float(tlas_sah)
    blas = np.asarray(mesh_sah, np.float64)[np.asarray(mesh_of, np.int64)]
    return float(tlas_sah + np.sum(areas / root * (blas - 1.0)))


def two_level_sah_cost_per_depth(tlas, mesh_of, mesh_per_depth: list[list[float]], mesh_sah) -> list[float]:
    """A two-level tree's SAH cost split by depth in the one tree the TLAS and the BLASes make
    together, each instance's TLAS leaf replaced by its BLAS's root: entry d sums A(n)/A(R) over
    the TLAS's internal nodes at depth d, and A(box_i)/A(R) · (BLAS cost at depth e) over every
    instance i whose leaf is at depth d_i and BLAS depth e with d_i + e = d (R: the TLAS's root;
    a BLAS's per-depth costs are relative to its own root box, as `two_level_sah_cost` takes
    them). The entries add up to `two_level_sah_cost` (within rounding), so a two-level row of
    Compare is read like a flat tree's: the cost a ray meets at each level of its walk.
    `tlas`: the TLAS as a Bvh (InstancedBvh.tlas; its references are instance indices); `mesh_of`:
    each instance's mesh; `mesh_per_depth[k]`: compare.tree_stats.sah_cost_per_depth of mesh k's
    tree (empty for an empty tree: its whole `mesh_sah[k]` at BLAS depth 0)."""
    nodes = tlas.nodes
    if len(nodes) == 0:
        return []
    area = box_areas(nodes["lo"], nodes["hi"])
    if not area[0] > 0:
        return []
    weight = area / area[0]
    depths = tlas.depths.astype(np.int64)
    leaf = tlas.is_leaf
    per_mesh = [
        np.asarray(d if len(d) else [s], np.float64) for d, s in zip(mesh_per_depth, mesh_sah)
    ]  # one instance per TLAS leaf (default_tlas_config)
    instance = tlas.refs[nodes["index"][leaf]].astype(np.int64)
    mesh = np.asarray(mesh_of, np.int64)[instance]
    height = int(depths.max()) + 1 + max((len(d) for d in per_mesh), default=1)
    out = np.bincount(depths[~leaf], weights=weight[~leaf], minlength=height).astype(np.float64)
    # the leaves' weights summed by (mesh, leaf depth): a BLAS's per-depth costs added once per pair
    pairs = mesh * height + depths[leaf]
    summed = np.bincount(pairs, weights=weight[leaf])
    for pair in np.flatnonzero(summed):
        k, d = divmod(int(pair), height)
        out[d : d + len(per_mesh[k])] += summed[pair] * per_mesh[k]
    last = np.flatnonzero(out)
    return out[: int(last[-1]) + 1].tolist() if len(last) else []


def instanced_stats(core_stats: dict, meshes: list, mesh_of: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> dict:
    """The core's TLAS stats plus the whole tree's: meshes' trees (each counted once) and what the
    instances make of them. `meshes`: the BLASes (bvhlab.Bvh); `mesh_of`: each instance's mesh;
    (lo, hi): the instances' world boxes."""
    per_mesh = [m.stats for m in meshes]
    uses = np.bincount(np.asarray(mesh_of, np.int64), minlength=len(meshes))
    d = dict(core_stats)
    d["mesh_primitives"] = [s["primitives"] for s in per_mesh]
    d["mesh_instances"] = uses.tolist()
    d["mesh_nodes"] = [s["nodes"] for s in per_mesh]
    d["mesh_height"] = [s["height"] for s in per_mesh]
    d["mesh_sah_cost"] = [s["sah_cost"] for s in per_mesh]
    d["mesh_memory_bytes"] = [s["memory_bytes"] for s in per_mesh]
    d["meshes_memory_bytes"] = sum(d["mesh_memory_bytes"])
    d["triangles"] = sum(s["triangles"] for s in per_mesh)  # stored: each mesh once
    d["spheres"] = sum(s["spheres"] for s in per_mesh)
    d["primitives"] = d["triangles"] + d["spheres"]
    d["triangles_flattened"] = int(sum(s["triangles"] * int(n) for s, n in zip(per_mesh, uses)))
    d["primitives_flattened"] = int(sum(s["primitives"] * int(n) for s, n in zip(per_mesh, uses)))
    d["nodes"] = d["tlas_nodes"] + sum(d["mesh_nodes"])
    d["leaves"] = sum(s["leaves"] for s in per_mesh)
    # levels a ray may descend: the TLAS's, then the deepest BLAS an instance places (a mesh of no
    # instance is reached by no ray: it counted, 25 levels for a TLAS of 1 and a placed mesh of 2)
    d["height"] = d["tlas_height"] + max((h for h, n in zip(d["mesh_height"], uses) if n), default=0)
    d["memory_bytes"] = d["tlas_memory_bytes"] + d["meshes_memory_bytes"]
    d["sah_cost"] = two_level_sah_cost(d["tlas_sah_cost"], lo, hi, mesh_of, d["mesh_sah_cost"])
    d["build_ms"] = d["tlas_build_ms"] + sum(s["build_ms"] for s in per_mesh)
    d["method"] = per_mesh[0]["method"] if per_mesh else ""
    return d
