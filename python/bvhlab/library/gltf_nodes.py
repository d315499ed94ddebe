"""A glTF 2.0 file's node hierarchy (Khronos, glTF 2.0 §3.5): checked to be the forest the
specification asks for (no node its own ancestor, none with two parents, a node's transform as a
matrix or as TRS, not both), and, where it is deep, flattened before trimesh reads it: one node a
mesh, placed by its world matrix (composed here, top-down, once a node). trimesh composes each
mesh's path through `numpy.linalg.multi_dot`, whose chain-order search is pure Python and cubic in
the path's length and recursive: a 52 KB file of a 1,000-node chain took 54 s and then failed at
Python's recursion limit, a 25 KB chain of 400 meshes over 300 s (a helper's audit)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from .._npz import SceneFileError

#: Hierarchies deeper than this are flattened (trimesh reads shallower ones fast, as they are).
FLAT_DEPTH = 8


def flatten_deep_nodes(path: Path, doc: dict) -> bool:
    """Checks the node forest of `doc` (the parsed glTF JSON) and, where some scene's hierarchy is
    deeper than FLAT_DEPTH, replaces its nodes with one node a placed mesh, in the order trimesh
    reads them (its meshes' triangles come out in the same order). Returns whether `doc` changed.
    SceneFileError for a cycle, a node with two parents, a node with a matrix and TRS, or a scene
    that lists a node and one of its ancestors (trimesh placed such a node once; flattened, twice)."""
    nodes = doc.get("nodes")
    if not isinstance(nodes, list) or not nodes:
        return False
    children = [_children(path, nodes, n) for n in range(len(nodes))]
    parent = [-1] * len(nodes)
    for n, kids in enumerate(children):
        for c in kids:
            if parent[c] != -1:
                raise SceneFileError(
                    f"{path}: node {c} is a child of nodes {parent[c]} and {n}: glTF nodes form trees (§3.5.3)"
                )
            parent[c] = n
    depth = _depths(path, children, parent)
    scenes = [s for s in doc.get("scenes") or [] if isinstance(s, dict)]
    if max(depth) < FLAT_DEPTH:
        return False
    flat: list[dict] = []
    for k, scene in enumerate(scenes):
        listed = scene.get("nodes") or []
        if not isinstance(listed, list) or not all(isinstance(r, int) and 0 <= r < len(nodes) for r in listed):
            raise SceneFileError(f"{path}: scene {k}'s nodes {listed!r} are not nodes of the file ({len(nodes)})")
        roots = list(dict.fromkeys(listed))  # one placement a node, as trimesh's
        _check_roots(path, k, roots, parent)
        placed = _placed(path, nodes, children, roots)
        first = len(flat)
        flat.extend(reversed(placed))  # trimesh reads a flat list from its end, as it walks a tree
        scene["nodes"] = list(range(first, len(flat)))
    doc["nodes"] = flat
    return True


def _check_roots(path: Path, k: int, roots: list[int], parent: list[int]) -> None:
    listed = set(roots)
    for r in roots:
        above = parent[r]
        while above != -1:
            if above in listed:
                raise SceneFileError(
                    f"{path}: scene {k} lists node {r} and its ancestor {above} (a scene's nodes are roots, §3.5.1)"
                )
            above = parent[above]


def _children(path: Path, nodes: list, n: int) -> list[int]:
    node = nodes[n] if isinstance(nodes[n], dict) else {}
    kids = node.get("children") or []
    if not isinstance(kids, list) or not all(isinstance(c, int) and 0 <= c < len(nodes) for c in kids):
        raise SceneFileError(f"{path}: node {n}'s children {kids!r} are not nodes of the file ({len(nodes)})")
    if "matrix" in node and any(key in node for key in ("translation", "rotation", "scale")):
        raise SceneFileError(f"{path}: node {n} has both a matrix and TRS (glTF 2.0 §3.5.2: one or the other)")
    return kids


def _depths(path: Path, children: list[list[int]], parent: list[int]) -> list[int]:
    """Each node's depth (a root's 0); SceneFileError for a node that is its own ancestor (a cycle
    has no root, so a node no walk from the roots reaches is in one)."""
    depth = [-1] * len(children)
    stack = [(n, 0) for n in range(len(children)) if parent[n] == -1]
    while stack:
        n, d = stack.pop()
        depth[n] = d
        stack.extend((c, d + 1) for c in children[n])
    if -1 in depth:
        raise SceneFileError(
            f"{path}: node {depth.index(-1)} is its own ancestor, or below one that is (glTF nodes form trees, §3.5.3)"
        )
    return depth


def _placed(path: Path, nodes: list, children: list[list[int]], roots: list[int]) -> list[dict]:
    """A node for each mesh below `roots`, placed by its world matrix, in the order of trimesh's
    walk (a stack: the last root first, then each node's last child first)."""
    placed = []
    stack = [(r, np.eye(4)) for r in roots]
    while stack:
        n, world = stack.pop()
        node = nodes[n] if isinstance(nodes[n], dict) else {}
        world = world @ _local(path, n, node)
        if "mesh" in node:
            mesh = {"mesh": node["mesh"], "matrix": [float(x) for x in world.T.reshape(-1)]}
            if "weights" in node:
                mesh["weights"] = node["weights"]
            placed.append(mesh)
        stack.extend((c, world) for c in children[n])
    return placed


def _local(path: Path, n: int, node: dict) -> np.ndarray:
    """A node's local transform (§3.5.2): its column-major matrix, else T · R · S (a quaternion
    x, y, z, w, normalised; none where its squared length is below 4 ε, as trimesh's
    quaternion_matrix: 1e-9 was a turn of 180°)."""
    try:
        if "matrix" in node:
            m = np.asarray(node["matrix"], np.float64)
            if m.shape != (16,):
                raise ValueError("a matrix has 16 numbers")
            out = m.reshape(4, 4).T
        else:
            t = np.asarray(node.get("translation", (0, 0, 0)), np.float64).reshape(3)
            x, y, z, w = np.asarray(node.get("rotation", (0, 0, 0, 1)), np.float64).reshape(4)
            s = np.asarray(node.get("scale", (1, 1, 1)), np.float64).reshape(3)
            out = np.eye(4)
            out[:3, :3] = _rotation(x, y, z, w) * s
            out[:3, 3] = t
    except (TypeError, ValueError) as e:
        raise SceneFileError(f"{path}: node {n}'s transform cannot be read ({e})") from None
    if not np.isfinite(out).all():
        raise SceneFileError(f"{path}: node {n}'s transform is not finite")
    return out


def _rotation(x: float, y: float, z: float, w: float) -> np.ndarray:
    squared = x * x + y * y + z * z + w * w
    if not squared >= 4 * np.finfo(np.float64).eps:  # NaN too: none, as trimesh's
        return np.eye(3)
    norm = math.sqrt(squared)
    x, y, z, w = x / norm, y / norm, z / norm, w / norm
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )
