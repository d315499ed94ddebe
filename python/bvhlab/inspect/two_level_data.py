"""A two-level tree's node figures as those of one tree (issue 35 on issue 34's trees): the tree
the TLAS and the meshes' trees make together, each instance's TLAS leaf replaced by its mesh's
tree moved into the world — the tree `two_level_stats.two_level_sah_cost` and
`two_level_sah_cost_per_depth` cost. A mesh tree's figures are relative to its own root box, so a
node of instance i weighs A(world box of i) / A(TLAS root) in the whole tree's SAH cost (exact
for translations, the usual estimate otherwise; MacDonald and Booth 1990). What the viewport's
measure colouring, the sidebar's cost breakdown and `bvhlab inspect --worst` read."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..two_level_stats import box_areas
from .levels import BLAS, TLAS, ShownBoxes, TreeNode
from .measures import MEASURES, Legend, ramp
from .node_data import NodeData


@dataclass(frozen=True)
class TwoLevelNodeData:
    """The TLAS's and each mesh tree's NodeData and what joins them; arrays by instance or by
    TLAS node (read-only)."""

    tlas: NodeData
    meshes: tuple[NodeData, ...]
    mesh_of: np.ndarray  #: (N,) int64 each instance's mesh
    leaf_of: np.ndarray  #: (N,) int64 the TLAS leaf holding each instance (-1: an empty mesh's)
    weight: np.ndarray  #: (N,) A(instance's world box) / A(TLAS root): its mesh tree's SAH → the whole tree's
    epo_weight: np.ndarray  #: (N,) the instance's surface in the world (its mesh's A(Q) × area scale)
    tlas_subtree_sah: np.ndarray  #: (T,) the whole tree's SAH cost under each TLAS node
    tlas_prims: np.ndarray  #: (T,) primitives under each TLAS node, once per instance
    sah_cost: float  #: the whole tree's SAH cost (= InstancedBvh.stats["sah_cost"])
    epo_total: float  #: Σ over instances of their mesh tree's EPO × epo_weight (the EPO shares' denominator)

    @classmethod
    def of(cls, bvh) -> TwoLevelNodeData:
        """The figures of a bvhlab.InstancedBvh (analyses each mesh tree once: Bvh.node_data)."""
        bvh = bvh.snapshot()  # one TLAS and one set of meshes throughout (another thread may place)
        tlas = bvh.tlas_node_data()
        meshes = tuple(m.node_data() for m in bvh.meshes)
        mesh_of = np.asarray(bvh.instances[0], np.int64)
        leaf_of = bvh.tlas_leaves_of_instances()
        world_lo, world_hi = bvh.world_boxes()
        root = float(tlas.area[0]) if len(tlas) else 0.0
        world = box_areas(world_lo, world_hi)
        weight = world / root if root > 0 else np.zeros(len(mesh_of))
        mesh_root = np.array([d.area[0] if len(d) else 0.0 for d in meshes], np.float64)[mesh_of]
        surface = np.array([d.surface_area for d in meshes], np.float64)[mesh_of]
        scale = np.divide(world, mesh_root, out=np.zeros_like(world), where=mesh_root > 0)
        epo_weight = surface * scale
        mesh_sah = np.array([d.sah_cost for d in meshes], np.float64)[mesh_of]
        mesh_epo = np.array([d.epo_cost for d in meshes], np.float64)[mesh_of]
        # each instance's one primitive in its TLAS leaf becomes its mesh tree's cost
        held = leaf_of >= 0
        extra = np.zeros(len(tlas))
        np.add.at(extra, leaf_of[held], (weight * (mesh_sah - 1.0))[held])
        prims = np.zeros(len(tlas))
        mesh_prims = np.array([d.prim_count[0] if len(d) else 0 for d in meshes], np.float64)[mesh_of]
        np.add.at(prims, leaf_of[held], mesh_prims[held])
        _sum_up(tlas, extra)
        _sum_up(tlas, prims)
        subtree = np.asarray(tlas.subtree_sah, np.float64) + extra
        for a in (mesh_of, leaf_of, weight, epo_weight, subtree, prims):
            a.flags.writeable = False
        return cls(
            tlas,
            meshes,
            mesh_of,
            leaf_of,
            weight,
            epo_weight,
            subtree,
            prims.astype(np.int64),
            float(subtree[0]) if len(subtree) else 0.0,
            float(np.sum(mesh_epo * epo_weight)),
        )

    def mesh_data(self, instance: int) -> NodeData:
        return self.meshes[int(self.mesh_of[instance])]

    def subtree_sah(self, node: TreeNode) -> float:
        """The whole tree's SAH cost under a node (a TLAS leaf's includes its instances' trees)."""
        if node.level == "tlas":
            return float(self.tlas_subtree_sah[node.node])
        return float(self.weight[node.instance] * self.mesh_data(node.instance).subtree_sah[node.node])

    def depth(self, node: TreeNode) -> int:
        """Depth in the whole tree (a mesh tree's root at its instance's TLAS leaf's depth)."""
        if node.level == "tlas":
            return int(self.tlas.depth[node.node])
        return int(self.tlas.depth[self.leaf_of[node.instance]]) + int(self.mesh_data(node.instance).depth[node.node])

    def figures(self, node: TreeNode) -> dict:
        """One node's figures as plain Python values (what `bvhlab inspect --node` prints): its own
        tree's NodeData.node (a mesh tree's box in the mesh's space) with the whole tree's depth,
        SAH cost under it and share of the whole tree's SAH."""
        if node.level == "tlas":
            out = {"level": "tlas", **self.tlas.node(node.node)}
            out["prim_count"] = int(self.tlas_prims[node.node])
        else:
            if not 0 <= node.instance < len(self.mesh_of):
                raise ValueError(f"instance {node.instance} does not exist; the scene has 0..{len(self.mesh_of) - 1}")
            if self.leaf_of[node.instance] < 0:
                raise ValueError(f"instance {node.instance}'s mesh is empty: it has no tree")
            mesh = int(self.mesh_of[node.instance])
            out = {"level": "blas", "instance": node.instance, "mesh": mesh, **self.meshes[mesh].node(node.node)}
            out["tlas_leaf"] = int(self.leaf_of[node.instance])
            out["depth_in_mesh_tree"] = out["depth"]
        out["depth"] = self.depth(node)
        out["subtree_sah"] = self.subtree_sah(node)
        out["sah_share"] = out["subtree_sah"] / self.sah_cost if self.sah_cost > 0 else 0.0
        return out

    def raw(self, shown: ShownBoxes, measure: str) -> np.ndarray:
        """Each shown box's value of `measure` before the ramp, as measures._raw gives a flat
        tree's: its subtree's share of the whole tree's SAH, its primitives, its children's
        overlap (within its own tree), its share of the scene's EPO (within each instance: the
        EPO of one instance's triangles inside another's boxes is not counted; TLAS boxes 0)."""
        if measure not in MEASURES:
            raise ValueError(f"measure must be one of {', '.join(MEASURES)}, got {measure!r}")
        out = np.zeros(len(shown.level), np.float64)
        top = np.flatnonzero(shown.level == TLAS)
        t = shown.node[top]
        out[top] = {
            "sah_share": self.tlas_subtree_sah[t] / self.sah_cost if self.sah_cost > 0 else 0.0,
            "leaf_size": self.tlas_prims[t],
            "child_overlap": self.tlas.child_overlap[t],
            "epo": 0.0,
        }[measure]
        blas = np.flatnonzero(shown.level == BLAS)
        inst = shown.instance[blas].astype(np.int64)
        for k, data in enumerate(self.meshes):
            at = np.flatnonzero(self.mesh_of[inst] == k)
            if not len(at):
                continue
            i, b = inst[at], shown.node[blas[at]]
            if measure == "sah_share":
                v = self.weight[i] * data.subtree_sah[b] / self.sah_cost if self.sah_cost > 0 else 0.0
            elif measure == "leaf_size":
                v = data.prim_count[b]
            elif measure == "child_overlap":
                v = data.child_overlap[b]
            else:
                v = self.epo_weight[i] * data.epo[b] / self.epo_total if self.epo_total > 0 else 0.0
            out[blas[at]] = v
        return out

    def values(self, shown: ShownBoxes, measure: str) -> tuple[np.ndarray, Legend]:
        """The shown boxes' values on the heat ramp and the legend (measures.ramp: one mapping)."""
        return ramp(self.raw(shown, measure), measure)

    def costliest(self, k: int, depth: int | None = None) -> list[tuple[TreeNode, float]]:
        """The k nodes of the whole tree (at `depth` of it, or anywhere) whose subtrees cost the
        most SAH, with their costs, largest first. A TLAS leaf stands for its instance's mesh tree
        root, so it is not listed itself (the root of that tree is)."""
        k = max(0, int(k))
        found: list[tuple[float, int, int, int]] = []  # (-cost, instance or -1, node, order)
        tlas_inner = np.flatnonzero(self.tlas.left >= 0)
        if depth is not None:
            tlas_inner = tlas_inner[self.tlas.depth[tlas_inner] == depth]
        for n in tlas_inner[np.argsort(-self.tlas_subtree_sah[tlas_inner], kind="stable")[:k]]:
            found.append((-float(self.tlas_subtree_sah[n]), -1, int(n), 0))
        held = np.flatnonzero(self.leaf_of >= 0)
        leaf_depth = self.tlas.depth[self.leaf_of[held]].astype(np.int64)
        for m, data in enumerate(self.meshes):
            if not len(data):
                continue
            mine = held[self.mesh_of[held] == m]
            depths = leaf_depth[self.mesh_of[held] == m]
            for d0 in np.unique(depths) if depth is not None else [None]:
                group = mine if d0 is None else mine[depths == d0]
                nodes = np.arange(len(data)) if d0 is None else np.flatnonzero(data.depth == depth - d0)
                if not len(nodes) or not len(group):
                    continue
                nodes = nodes[np.lexsort((nodes, -data.subtree_sah[nodes]))[:k]]
                group = group[np.lexsort((group, -self.weight[group]))[:k]]
                cost = self.weight[group][:, None] * data.subtree_sah[nodes][None, :]
                for gi, ni in zip(*np.unravel_index(np.argsort(-cost, axis=None, kind="stable")[:k], cost.shape)):
                    found.append((-float(cost[gi, ni]), int(group[gi]), int(nodes[ni]), 1))
        found.sort(key=lambda f: (f[0], f[3], f[1], f[2]))
        return [(TreeNode("tlas", n) if i < 0 else TreeNode("blas", n, i), -c) for c, i, n, _ in found[:k]]


def _sum_up(tlas: NodeData, values: np.ndarray) -> None:
    """Add each node's value into its ancestors', deepest level first (in place)."""
    depth = np.asarray(tlas.depth, np.int64)
    for d in range(int(depth.max(initial=0)), 0, -1):
        at = np.flatnonzero(depth == d)
        np.add.at(values, tlas.parent[at], values[at])
