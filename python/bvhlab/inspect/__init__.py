"""Inspecting a tree (issue 35): every node's data (`NodeData`), what one ray's traversal did
(`RayRecord`), and trees saved to files (`save_bvh`, `load_bvh`)."""
