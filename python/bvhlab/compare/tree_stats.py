"""Per-depth figures of a built tree that `Bvh.stats` does not carry, from its nodes."""

from __future__ import annotations

import numpy as np


def sah_cost_per_depth(bvh) -> list[float]:
    """The tree's SAH cost split by depth (root = 0): entry d sums, over the nodes at depth d,
    A(n)/A(R)·C_trav for an internal node and A(n)/A(R)·N(n)·C_isect for a leaf, C_trav = C_isect
    = 1 — the formula of `Bvh.stats["sah_cost"]` (README, "Stats and conventions"), so the entries
    add up to it. Empty when the tree is empty; where the root box has no area (primitives on a
    line or a point) every node's A(n)/A(R) is 1, as the core's sah_term (stats.h) counts it."""
    nodes = bvh.nodes
    if len(nodes) == 0:
        return []
    extent = nodes["hi"].astype(np.float64) - nodes["lo"].astype(np.float64)
    area = 2.0 * (extent[:, 0] * extent[:, 1] + extent[:, 1] * extent[:, 2] + extent[:, 2] * extent[:, 0])
    share = area / area[0] if area[0] > 0 else np.ones(len(area))
    leaf = bvh.is_leaf
    weight = np.where(leaf, nodes["info"].astype(np.float64), 1.0)  # a leaf's info is its primitive count
    return np.bincount(bvh.depths, weights=share * weight).tolist()
