"""Measures a tree's boxes can be coloured by (issue 35: box edges by SAH share, leaf size, child
overlap or EPO, with a legend): each node's value mapped to [0, 1] for the heat ramp
(`bvhlab._core.heat_colors`: blue 0 → red 1), and the legend that says what the ends mean. One
definition for every drawer (the add-on's viewport overlay; images that colour by a measure)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .node_data import NodeData

#: name → (label, what it is); "depth" is the palette colouring, not a measure of this module.
MEASURES = {
    "sah_share": ("SAH share", "The subtree's share of the tree's SAH cost (log scale)"),
    "leaf_size": ("Primitives", "Primitives under the node; for leaves, the leaf size (log scale)"),
    "child_overlap": ("Child overlap", "Surface area of the children's overlap over the node's (linear)"),
    "epo": ("EPO", "The node's end-point overlap term, share of the tree's EPO (log scale)"),
}
#: How many decades of a log scale the ramp spans below its largest value.
LOG_DECADES = 5.0


@dataclass(frozen=True)
class Legend:
    """What the ramp's blue and red ends stand for."""

    measure: str
    low: float
    high: float
    log: bool

    def text(self) -> str:
        scale = "log" if self.log else "linear"
        return f"blue {self.low:.2g} – red {self.high:.2g}, {scale}"


def _raw(data: NodeData, measure: str) -> np.ndarray:
    if measure == "sah_share":
        return np.asarray(data.sah_share, np.float64)
    if measure == "leaf_size":
        return np.asarray(data.prim_count, np.float64)
    if measure == "child_overlap":
        return np.asarray(data.child_overlap, np.float64)
    if measure == "epo":
        return np.asarray(data.epo, np.float64) / data.epo_cost if data.epo_cost > 0 else np.zeros(len(data))
    raise ValueError(f"measure must be one of {', '.join(MEASURES)}, got {measure!r}")


def measure_values(data: NodeData, measure: str, nodes: np.ndarray | None = None) -> tuple[np.ndarray, Legend]:
    """Each node's (or each of `nodes`') value in [0, 1] on the ramp, and its legend. Log scales
    span LOG_DECADES below the largest value among the nodes coloured; zero maps to 0."""
    raw = _raw(data, measure)
    return ramp(raw if nodes is None else raw[nodes], measure)


def ramp(raw: np.ndarray, measure: str) -> tuple[np.ndarray, Legend]:
    """Raw values of `measure` (as `_raw` gives them: shares, counts, overlaps) on the ramp, and
    the legend: the one mapping of a flat tree's nodes and a two-level tree's boxes."""
    if measure not in MEASURES:
        raise ValueError(f"measure must be one of {', '.join(MEASURES)}, got {measure!r}")
    if measure == "child_overlap":
        return np.clip(raw, 0.0, 1.0).astype(np.float32), Legend(measure, 0.0, 1.0, False)
    high = float(raw.max()) if len(raw) else 0.0
    if high <= 0:
        return np.zeros(len(raw), np.float32), Legend(measure, 0.0, 0.0, True)
    floor = 1.0 if measure == "leaf_size" else high * 10.0**-LOG_DECADES
    low = min(floor, high)
    span = np.log(high / low) if high > low else 1.0
    with np.errstate(divide="ignore"):
        v = np.log(np.maximum(raw, low) / low) / span
    v = np.where(raw > 0, v, 0.0)
    return np.clip(v, 0.0, 1.0).astype(np.float32), Legend(measure, low, high, True)


def box_order(data: NodeData, leaves_only: bool = False) -> np.ndarray:
    """The nodes in the order of `Bvh.boxes` (by depth, depth-first within a depth), only the
    leaves when `leaves_only`: the rows of a box table."""
    nodes = np.flatnonzero(data.left < 0) if leaves_only else np.arange(len(data))
    return nodes[np.lexsort((nodes, data.depth[nodes]))]
