"""`NodeData`: every node's box, place in the tree and costs, made in C++ for all nodes at once
(core_cpp/include/bvhlab/node_data.h, one definition of each figure)."""

from __future__ import annotations

from dataclasses import dataclass, fields

import numpy as np

from .. import _checks


@dataclass(frozen=True)
class NodeData:
    """Arrays indexed by node (depth-first order, root 0; read-only). Costs use the tree's one SAH
    formula (`Bvh.stats["sah_cost"]`: C_trav = C_isect = 1, areas relative to the root's)."""

    lo: np.ndarray  #: (N, 3) float32, the box
    hi: np.ndarray  #: (N, 3) float32
    depth: np.ndarray  #: uint8, root 0
    parent: np.ndarray  #: int32, -1 for the root
    left: np.ndarray  #: int32 first child (i + 1), -1 for a leaf
    right: np.ndarray  #: int32 second child, -1 for a leaf
    prim_count: np.ndarray  #: uint32 primitives in the subtree
    area: np.ndarray  #: float64 surface area of the box
    sah_term: np.ndarray  #: float64 the node's own term of the SAH cost
    subtree_sah: np.ndarray  #: float64 Σ sah_term over the subtree (the root's is the tree's SAH cost)
    sah_share: np.ndarray  #: float64 subtree_sah / SAH cost
    child_overlap: np.ndarray  #: float64 area(left ∩ right) / area(node); 0 for a leaf
    epo: np.ndarray  #: float64 end-point overlap term (Aila, Karras and Laine 2013; triangles only), NaN not made
    sah_cost: float  #: Σ sah_term
    epo_cost: float  #: Σ epo (NaN where not made: Bvh.node_data(epo=False))
    surface_area: float  #: A(Q), the triangles' area: what EPO terms are shares of (0 for a TLAS)

    @classmethod
    def from_core(cls, d: dict) -> NodeData:
        values = {}
        for f in fields(cls):
            v = d[f.name]
            if isinstance(v, np.ndarray):
                v.flags.writeable = False
            values[f.name] = v
        return cls(**values)

    @property
    def has_epo(self) -> bool:
        """Whether the EPO terms were made (Bvh.node_data(epo=True))."""
        return not np.isnan(self.epo_cost)

    def __len__(self) -> int:
        return len(self.depth)

    def is_leaf(self, node: int) -> bool:
        return bool(self.left[node] < 0)

    def node(self, node: int) -> dict:
        """One node's figures as plain Python values (what the CLI prints and writes)."""
        node = _checks.integer("node", node, -(2**63), 2**63 - 1)  # True, 1.5: TypeError, not numpy's
        if not 0 <= node < len(self):
            raise ValueError(f"node {node} does not exist; the tree has nodes 0..{len(self) - 1}")
        out: dict = {"node": int(node), "leaf": self.is_leaf(node)}
        for f in fields(self):
            v = getattr(self, f.name)
            if isinstance(v, np.ndarray):
                out[f.name] = v[node].tolist()
        return out

    def costliest_at_depth(self, depth: int, k: int) -> np.ndarray:
        """The k nodes of one depth whose subtrees cost the most SAH, largest first (ties: the lower
        index): where a tree at that depth is expensive."""
        depth = _checks.integer("depth", depth, -(2**63), 2**63 - 1)
        k = _checks.integer("k", k, -(2**63), 2**63 - 1)  # 2.7 was taken as 2
        at = np.flatnonzero(self.depth == depth)
        order = np.lexsort((at, -self.subtree_sah[at]))
        return at[order[: max(0, k)]]

    def worst(self, k: int) -> np.ndarray:
        """The k nodes whose subtrees cost the most SAH, largest first (ties: the lower index). A
        subtree costs at least as much as any below it, so the root comes first and a node's
        ancestors before it."""
        k = _checks.integer("k", k, -(2**63), 2**63 - 1)
        order = np.lexsort((np.arange(len(self)), -self.subtree_sah))
        return order[: max(0, k)]
