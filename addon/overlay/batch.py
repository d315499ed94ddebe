"""The boxes of a tree on the GPU, ready to draw any depth range with one instanced call."""
from __future__ import annotations

import numpy as np

from .shader import box_shader

#: The 12 edges of the unit cube as 24 corners in {0,1}³ (mixed between a box's min and max).
CUBE_EDGES = np.array([
    (0, 0, 0), (1, 0, 0), (0, 1, 0), (1, 1, 0), (0, 0, 1), (1, 0, 1), (0, 1, 1), (1, 1, 1),  # along x
    (0, 0, 0), (0, 1, 0), (1, 0, 0), (1, 1, 0), (0, 0, 1), (0, 1, 1), (1, 0, 1), (1, 1, 1),  # along y
    (0, 0, 0), (0, 0, 1), (1, 0, 0), (1, 0, 1), (0, 1, 0), (0, 1, 1), (1, 1, 0), (1, 1, 1),  # along z
], np.float32)

#: The widest texture rows GPUs must support (GL_MAX_TEXTURE_SIZE ≥ 16384 on GL 4.5 hardware).
TEXTURE_WIDTH = 16384


def box_table(bvh, leaves_only: bool = False, rows_multiple_of: int = 1) -> np.ndarray:
    """float32 (N, 8) rows (min.xyz, depth, max.xyz, is_leaf) of the tree's nodes sorted by depth
    (depth-first order within a depth, as `Bvh.boxes`), only leaves when `leaves_only`; then
    copies of the last row up to a multiple of `rows_multiple_of` (texture padding, never drawn)."""
    depths = bvh.depths
    order = np.argsort(depths, kind="stable")
    is_leaf = bvh.is_leaf[order]
    if leaves_only:
        order, is_leaf = order[is_leaf], is_leaf[is_leaf]
    count = len(order)
    padding = -count % rows_multiple_of
    if padding:
        order = np.concatenate([order, np.full(padding, order[-1] if count else 0, order.dtype)])
    # A node is 32 bytes (lo, index, hi, info): taking whole 32-byte records is several times
    # faster than gathering the structured fields; the two integer slots are then overwritten.
    table = np.take(bvh.nodes.view(np.dtype("V32")).reshape(-1), order).view(np.float32).reshape(-1, 8)
    table[:, 3] = depths[order]
    table[:count, 7] = is_leaf
    return table


def depth_slice(sorted_depths: np.ndarray, depth_min: int, depth_max: int) -> tuple[int, int]:
    """(first, count) of the rows whose depth d satisfies depth_min <= d <= depth_max."""
    first, last = np.searchsorted(sorted_depths, [depth_min, depth_max + 1])
    return int(first), int(last - first)


class BoxBatch:
    """A tree's boxes in an RGBA32F texture plus a 24-vertex line batch. Made when the tree or the
    leaves-only choice changes; a depth range is then only an offset and a count (report §3.3.1)."""

    def __init__(self, table: np.ndarray, count: int):
        """`table`: box_table rows, the first `count` real, padded to whole texture rows."""
        import gpu
        from gpu_extras.batch import batch_for_shader

        self.count = count
        self.depths = table[:count, 3].astype(np.uint8)  # sorted: a depth range is a slice
        width = min(TEXTURE_WIDTH, max(2 * len(table), 2))
        height = -(-2 * len(table) // width)
        assert width * height == 2 * len(table), "table rows must fill whole texture rows"
        self.texture = gpu.types.GPUTexture((width, height), format="RGBA32F",
                                            data=gpu.types.Buffer("FLOAT", table.size, table.reshape(-1)))
        self.shader = box_shader()
        self.batch = batch_for_shader(self.shader, "LINES", {"corner": CUBE_EDGES})

    @classmethod
    def from_bvh(cls, bvh, leaves_only: bool = False) -> "BoxBatch":
        count = bvh.stats["leaves" if leaves_only else "nodes"]
        rows_per_texture_row = TEXTURE_WIDTH // 2
        table = box_table(bvh, leaves_only, rows_per_texture_row if count > rows_per_texture_row else 1)
        return cls(table, count)

    def draw(self, view_projection, depth_min: int, depth_max: int, *, color=(1.0, 0.55, 0.1, 1.0),
             color_by_depth: bool = True, xray: bool = True, line_width: float = 1.0) -> int:
        """Draw the boxes in the depth range with the current framebuffer; returns how many."""
        import gpu

        first, count = depth_slice(self.depths, depth_min, depth_max)
        if count == 0:
            return 0
        shader = self.shader
        shader.bind()
        shader.uniform_sampler("boxes", self.texture)
        shader.uniform_float("view_projection", view_projection)
        shader.uniform_float("uniform_color", tuple(color))
        shader.uniform_int("first_box", first)
        shader.uniform_int("color_by_depth", int(color_by_depth))
        gpu.state.blend_set("ALPHA")
        gpu.state.depth_test_set("NONE" if xray else "LESS_EQUAL")
        gpu.state.line_width_set(line_width)
        try:
            self.batch.draw_instanced(shader, instance_start=0, instance_count=count)
        finally:
            gpu.state.line_width_set(1.0)
            gpu.state.depth_test_set("NONE")
            gpu.state.blend_set("NONE")
        return count
