"""The boxes of a tree on the GPU, ready to draw any depth range with one instanced call. The
boxes, their depth order and the depth palette all come from the core (`Bvh.boxes`,
`bvhlab._core.depth_colors`); this module only lays them out for Blender's `gpu` module."""

from __future__ import annotations

import numpy as np

from .shader import box_shader

#: The 12 edges of the unit cube as 24 corners in {0,1}³ (mixed between a box's min and max).
CUBE_EDGES = np.array(
    [
        (0, 0, 0),
        (1, 0, 0),
        (0, 1, 0),
        (1, 1, 0),
        (0, 0, 1),
        (1, 0, 1),
        (0, 1, 1),
        (1, 1, 1),  # along x
        (0, 0, 0),
        (0, 1, 0),
        (1, 0, 0),
        (1, 1, 0),
        (0, 0, 1),
        (0, 1, 1),
        (1, 0, 1),
        (1, 1, 1),  # along y
        (0, 0, 0),
        (0, 0, 1),
        (1, 0, 0),
        (1, 0, 1),
        (0, 1, 0),
        (0, 1, 1),
        (1, 1, 0),
        (1, 1, 1),  # along z
    ],
    np.float32,
)

#: The widest texture rows GPUs must support (GL_MAX_TEXTURE_SIZE ≥ 16384 on GL 4.5 hardware).
TEXTURE_WIDTH = 16384
#: Depths the palette covers (trees are at most 64 levels deep: bvhlab.bvh.MAX_TREE_HEIGHT).
PALETTE_SIZE = 64


class BoxTable:
    """float32 rows (min.xyz, depth, max.xyz, value) of a tree's boxes in the core's depth order
    (`Bvh.boxes`: by depth, depth-first within a depth), only the leaves when `leaves_only`, and
    where each depth starts, so a depth range is one offset and one count (report §3.3.1)."""

    def __init__(self, bvh, leaves_only: bool = False, measure: str = "depth"):
        lo, hi, depth = bvh.boxes(leaves_only=leaves_only)
        self._fill(lo, hi, depth, bvh.stats["leaves_per_depth" if leaves_only else "nodes_per_depth"])
        if measure != "depth":  # each box's value on the heat ramp in the spare column
            from bvhlab.inspect.measures import box_order, measure_values

            data = bvh.cached_node_data()
            assert data is not None, "a measure colouring needs the tree analysed (Bvh.node_data)"
            self.rows[:, 7], self.legend = measure_values(data, measure, box_order(data, leaves_only))

    @classmethod
    def from_boxes(cls, lo: np.ndarray, hi: np.ndarray, depth: np.ndarray, note: str = "") -> BoxTable:
        """A table of boxes already sorted by depth (a two-level tree's: overlay/levels.py)."""
        table = cls.__new__(cls)
        table._fill(lo, hi, depth, np.bincount(depth, minlength=1))
        table.note = note
        return table

    def _fill(self, lo, hi, depth, per_depth) -> None:
        self.rows = np.zeros((len(lo), 8), np.float32)
        self.rows[:, 0:3], self.rows[:, 3], self.rows[:, 4:7] = lo, depth, hi
        self.legend = None
        self.note = ""  # what the table leaves out, for the panel
        self.depth_starts = np.concatenate([[0], np.cumsum(per_depth)]).astype(np.int64)
        assert self.depth_starts[-1] == len(self.rows), "stats and boxes disagree"

    def depth_slice(self, depth_min: int, depth_max: int) -> tuple[int, int]:
        """(first, count) of the rows whose depth d satisfies depth_min <= d <= depth_max."""
        deepest = len(self.depth_starts) - 1
        lo, hi = min(max(depth_min, 0), deepest), min(max(depth_max + 1, 0), deepest)
        first = int(self.depth_starts[lo])
        return first, max(int(self.depth_starts[hi]) - first, 0)

    def padded(self, rows_multiple_of: int) -> np.ndarray:
        """The rows, then zero rows up to a multiple of `rows_multiple_of` (texture padding, never drawn)."""
        padding = -len(self.rows) % rows_multiple_of
        return np.concatenate([self.rows, np.zeros((padding, 8), np.float32)]) if padding else self.rows


def depth_palette() -> np.ndarray:
    """RGBA float32 (PALETTE_SIZE, 4): the core's overlay colour of each depth (the Vulkan overlay
    pass and the CLI's pictures use the same one)."""
    from bvhlab._core import depth_colors

    rgb = depth_colors(np.arange(PALETTE_SIZE, dtype=np.uint32))
    return np.concatenate([rgb, np.ones((PALETTE_SIZE, 1), np.float32)], 1).astype(np.float32)


#: Entries of the heat ramp's texture (the core's heat_colors sampled evenly over [0, 1]).
HEAT_SIZE = 256


def heat_palette() -> np.ndarray:
    """RGBA float32 (HEAT_SIZE, 4): the core's heat ramp (the heatmap mode's), for measures."""
    from bvhlab._core import heat_colors

    rgb = heat_colors(np.linspace(0, 1, HEAT_SIZE, dtype=np.float32))
    return np.concatenate([rgb, np.ones((HEAT_SIZE, 1), np.float32)], 1).astype(np.float32)


#: The shader's colour modes.
UNIFORM, BY_DEPTH, BY_VALUE = 0, 1, 2


def _texture(rows: np.ndarray, width: int):
    import gpu

    texels = rows.reshape(-1, 4)
    height = len(texels) // width
    assert width * height == len(texels), "rows must fill whole texture rows"
    return gpu.types.GPUTexture(
        (width, height), format="RGBA32F", data=gpu.types.Buffer("FLOAT", texels.size, texels.reshape(-1))
    )


class BoxBatch:
    """A BoxTable in an RGBA32F texture (two texels per box), the depth palette in another, and a
    24-vertex line batch drawn once per box. Made when the tree or the leaves-only choice changes."""

    def __init__(self, table: BoxTable):
        from gpu_extras.batch import batch_for_shader

        self.table = table
        self.count = len(table.rows)
        rows = table.padded(TEXTURE_WIDTH // 2) if self.count > TEXTURE_WIDTH // 2 else table.padded(1)
        if len(rows) == 0:
            rows = np.zeros((1, 8), np.float32)
        self.texture = _texture(rows, min(TEXTURE_WIDTH, 2 * len(rows)))
        self.palette = _texture(depth_palette(), PALETTE_SIZE)
        self.heat = _texture(heat_palette(), HEAT_SIZE)
        self.shader = box_shader()
        self.batch = batch_for_shader(self.shader, "LINES", {"corner": CUBE_EDGES})

    @classmethod
    def from_bvh(cls, bvh, leaves_only: bool = False, measure: str = "depth") -> BoxBatch:
        return cls(BoxTable(bvh, leaves_only, measure))

    def draw(
        self,
        view_projection,
        depth_min: int,
        depth_max: int,
        *,
        color=(1.0, 0.55, 0.1, 1.0),
        color_by_depth: bool = True,
        xray: bool = True,
        line_width: float = 1.0,
    ) -> int:
        """Draw the boxes in the depth range with the current framebuffer; returns how many. A table
        made with a measure colours each box by its value (heat ramp), whatever `color_by_depth`.
        Deepest boxes first: a child shares edges with its parent, and drawn last it would paint
        them all in its colour; this way every depth of the range keeps its own lines."""
        import gpu

        first, count = self.table.depth_slice(depth_min, depth_max)
        if count == 0:
            return 0
        shader = self.shader
        shader.bind()
        shader.uniform_sampler("boxes", self.texture)
        shader.uniform_sampler("palette", self.palette)
        shader.uniform_sampler("heat", self.heat)
        shader.uniform_float("view_projection", view_projection)
        shader.uniform_float("uniform_color", tuple(color))
        shader.uniform_int("last_box", first + count - 1)
        mode = BY_VALUE if self.table.legend is not None else BY_DEPTH if color_by_depth else UNIFORM
        shader.uniform_int("color_mode", mode)
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
