"""Settings on each Scene (`scene.bvhlab`) and the "Analytic sphere" flag on objects."""

from __future__ import annotations

import bpy
from bpy.props import BoolProperty, EnumProperty, FloatProperty, FloatVectorProperty, IntProperty, StringProperty

from bvhlab.build_config import (
    DEFAULT_AXIS,
    DEFAULT_BIN_BOUNDS,
    DEFAULT_BINS,
    DEFAULT_MAX_LEAF_SIZE,
    DEFAULT_METHOD,
    DEFAULT_SAH_BLOCK,
    MAX_BINS,
    MAX_LEAF_SIZE,
    MIN_BINS,
)
from bvhlab.render import MAX_RAY_DEPTH, MAX_SAMPLES_PER_AXIS
from bvhlab.render_options import AUTO_TRAVERSAL, MAX_LINE_WIDTH, RenderOptions

from . import state
from .property_items import (
    AXIS_ITEMS,
    BACKEND_ITEMS,
    BIN_BOUNDS_ITEMS,
    COUNTER_ITEMS,
    DEFAULT_UPDATE_POLICY,
    MAX_DEPTH,
    MEASURE_ITEMS,
    METHOD_ITEMS,
    MODE_ITEMS,
    OVERLAY_LEVEL_ITEMS,
    SAH_BLOCK_ITEMS,
    TRAVERSAL_ITEMS,
    TWO_TREE_ITEMS,
    UPDATE_POLICY_ITEMS,
)

#: A render's defaults (the core's RenderSettings, through bvhlab.RenderOptions): the settings below
#: start from them.
_RENDER = RenderOptions()


def output_path_options() -> set[str]:
    """bpy.props options of a path the add-on writes to: an output path (the file browser asks for
    no existing file), and "//" meaning the .blend's folder (operator_support.output_path resolves
    it with bpy.path.abspath). Blender 4.5 added the option PATH_SUPPORTS_BLEND_RELATIVE; from then
    a path property without it warns, and Blender 5.2 draws its field red, when it holds "//";
    Blender 4.2 refuses the unknown option (registration fails), hence the test."""
    options = {"OUTPUT_PATH"}
    if "is_path_supports_blend_relative" in bpy.types.Property.bl_rna.properties:
        options.add("PATH_SUPPORTS_BLEND_RELATIVE")
    return options


def _redraw(_self=None, _context=None) -> None:
    """The update of every setting the 3D viewport shows (the overlay, the Rendered shading). A
    property without an update function is not updated at all when a script sets it (Blender's
    RNA_property_update_check): no depsgraph tag, so no view_update, and no redraw. With one,
    Blender tags the scene and redraws the windows; this also tags the 3D viewports."""
    from .overlay import tag_redraw

    tag_redraw()


def _depth_min_changed(self, context) -> None:
    built = state.tree_for(context.scene)
    if built is not None and self.overlay_depth_min > built.height - 1:
        self.overlay_depth_min = built.height - 1  # bounded by the tree's height
    if self.overlay_depth_max < self.overlay_depth_min:
        self.overlay_depth_max = self.overlay_depth_min
    _redraw()


def _depth_max_changed(self, context) -> None:
    built = state.tree_for(context.scene)
    if built is not None and self.overlay_depth_max > built.height - 1:
        self.overlay_depth_max = built.height - 1
    if self.overlay_depth_min > self.overlay_depth_max:
        self.overlay_depth_min = self.overlay_depth_max
    _redraw()


class BVHLAB_PG_settings(bpy.types.PropertyGroup):
    """Build, overlay, render and comparison settings of one scene."""

    scope: EnumProperty(
        name="Scope",
        default="visible",
        description="Which objects the tree is built over",
        items=[
            ("visible", "Visible", "Every object visible in the view layer"),
            ("selected", "Selected", "The selected objects only"),
        ],
    )
    method: EnumProperty(name="Split method", items=METHOD_ITEMS, default=DEFAULT_METHOD, update=_redraw)
    bins: IntProperty(
        name="Bins",
        min=MIN_BINS,
        max=MAX_BINS,
        default=DEFAULT_BINS,
        update=_redraw,
        description="SAH bins per axis (PBRT's default and the report's is 12)",
    )
    bin_bounds: EnumProperty(name="Buckets", items=BIN_BOUNDS_ITEMS, default=DEFAULT_BIN_BOUNDS, update=_redraw)
    axis: EnumProperty(name="Axis", items=AXIS_ITEMS, default=DEFAULT_AXIS, update=_redraw)
    max_leaf_size: IntProperty(
        name="Max leaf size",
        min=1,
        max=MAX_LEAF_SIZE,
        soft_max=16,
        default=DEFAULT_MAX_LEAF_SIZE,
        update=_redraw,
        description="Most primitives in a leaf; SAH methods may stop earlier (the report's trees: 1)",
    )
    sah_block: EnumProperty(
        name="SAH block",
        items=SAH_BLOCK_ITEMS,
        default=str(DEFAULT_SAH_BLOCK),
        update=_redraw,
        description="The SAH counts primitives in whole blocks of this many: 4, the triangles the CPU "
        "traversal tests at once; 1, one by one (the report's SAH)",
    )

    overlay_show: BoolProperty(
        name="Show boxes",
        default=False,
        update=_redraw,
        description="Draw the boxes of the nodes in the depth range in the viewport",
    )
    overlay_depth_min: IntProperty(
        name="Min depth",
        min=0,
        max=MAX_DEPTH,
        default=0,
        update=_depth_min_changed,
        description="Shallowest depth drawn (root = 0); at most the tree height - 1",
    )
    overlay_depth_max: IntProperty(
        name="Max depth",
        min=0,
        max=MAX_DEPTH,
        default=3,
        update=_depth_max_changed,
        description="Deepest depth drawn; at most the tree height - 1",
    )
    overlay_color_by_depth: BoolProperty(name="Colour by depth", default=_RENDER.color_by_depth, update=_redraw)
    overlay_measure: EnumProperty(
        name="Colour by",
        items=MEASURE_ITEMS,
        default="depth",
        update=_redraw,
        description="Colour the viewport's boxes by a measure of each node (blue low → red high; Inspect ▸ "
        "Analyse Tree computes them). Boxes traced into renders keep the depth or line colour",
    )
    overlay_color: FloatVectorProperty(
        name="Colour",
        subtype="COLOR",
        size=4,
        min=0.0,
        max=1.0,
        default=(*_RENDER.line_color, 1.0),
        update=_redraw,
        description="The boxes' colour when not coloured by depth (in the viewport and in traced images)",
    )
    overlay_leaves_only: BoolProperty(
        name="Leaves only", default=False, update=_redraw, description="Draw only the leaves in the depth range"
    )
    overlay_xray: BoolProperty(
        name="X-ray",
        default=True,
        update=_redraw,
        description="Draw boxes through geometry (off: hidden behind surfaces)",
    )
    overlay_line_width: FloatProperty(
        name="Line width", min=1.0, max=MAX_LINE_WIDTH, soft_max=5.0, default=_RENDER.line_width, update=_redraw
    )
    # Two-level trees (instanced scenes, issue 34): which level's boxes the viewport draws, and how
    # the tree of a mesh that moved or was edited is updated.
    overlay_level: EnumProperty(
        name="Level",
        items=OVERLAY_LEVEL_ITEMS,
        default="both",
        update=_redraw,
        description="Of a two-level tree (instanced scene): the boxes of the TLAS (over the instances), of the "
        "BLASes (each mesh's tree, moved into the world by each instance; the depth range applies within a "
        "BLAS), or both",
    )
    update_policy: EnumProperty(
        name="Update",
        items=UPDATE_POLICY_ITEMS,
        default=DEFAULT_UPDATE_POLICY,
        update=_redraw,
        description="How the viewport and F12 update the tree of a mesh that moved or was edited (same "
        "triangle count); moving an instance only rebuilds the TLAS",
    )

    light_distance: FloatProperty(
        name="Light Distance",
        min=0.0,
        default=0.0,
        soft_max=1000.0,
        subtype="DISTANCE",
        update=_redraw,
        description="The distance a point light's watts are calibrated by (intensity = W / (4π² d²)). 0: "
        "measured, the median distance from the light to the scene, once per render job at its first frame "
        "and once per viewport session; set it (Measure takes the current frame's) so that frames rendered "
        "in separate jobs, such as a render farm's chunks, are lit alike",
    )
    render_bounces: IntProperty(
        name="Bounces",
        min=0,
        max=MAX_RAY_DEPTH,
        default=_RENDER.max_depth,
        update=_redraw,
        description="Reflection and refraction depth of the Whitted tracer",
    )
    render_supersampling: IntProperty(
        name="Samples",
        min=1,
        max=MAX_SAMPLES_PER_AXIS,
        soft_max=8,
        default=_RENDER.samples_per_axis,
        update=_redraw,
        description="n × n samples per pixel",
    )
    backend: EnumProperty(
        name="Backend",
        default="auto",
        items=BACKEND_ITEMS,
        update=_redraw,
    )
    traversal: EnumProperty(
        name="Traversal",
        default=AUTO_TRAVERSAL,  # the fastest walk of the device, the same image (RenderOptions.for_backend)
        items=TRAVERSAL_ITEMS,
        update=_redraw,
    )
    render_mode: EnumProperty(
        name="Mode",
        default=_RENDER.mode,
        items=MODE_ITEMS,
        update=_redraw,
    )
    render_overlay: BoolProperty(
        name="Boxes in image", default=False, description="Draw the overlay's depth range into the rendered image"
    )
    viewport_counter: EnumProperty(
        name="Counter",
        items=COUNTER_ITEMS,
        default="none",
        update=_redraw,
        description="Rendered viewport: show a traversal counter per pixel on the heat ramp instead of the image",
    )
    counter_range_auto: BoolProperty(
        name="Auto Range",
        default=True,
        update=_redraw,
        description="The counter's colours span 0 to the 99th percentile of the frame",
    )
    counter_range_min: FloatProperty(
        name="Min", default=0.0, min=0.0, max=1e6, update=_redraw, description="Counter shown blue"
    )
    counter_range_max: FloatProperty(
        name="Max", default=64.0, min=0.0, max=1e6, update=_redraw, description="Counter shown red (and above)"
    )
    counter_diff_first: EnumProperty(
        name="First", items=TWO_TREE_ITEMS, default="median", description="Compare Two Trees: the tree subtracted from"
    )
    counter_diff_second: EnumProperty(
        name="Second", items=TWO_TREE_ITEMS, default="sah12", description="Compare Two Trees: the tree subtracted"
    )
    viewport_budget_ms: FloatProperty(
        name="Preview ms",
        min=5.0,
        max=1000.0,
        default=40.0,
        precision=0,
        update=_redraw,
        description=(
            "Rendered viewport: while the view moves, trace at the resolution that takes about this many "
            "milliseconds; full resolution (then n × n samples) once it stops"
        ),
    )

    compare_frames: IntProperty(
        name="Frames", min=1, max=50, default=3, description="Renders per method; the frame time is their mean"
    )
    compare_filepath: StringProperty(
        name="Table",
        subtype="FILE_PATH",
        options=output_path_options(),
        default="//bvh_compare.csv",
        description="CSV file the comparison is written to",
    )

    def build_config(self):
        """The build these settings ask for, as the one typed object (bvhlab.BuildConfig) the
        sidebar's Build, Render and Export, F12, the viewport and Compare all pass to the core."""
        from bvhlab.build_config import BuildConfig

        return BuildConfig(
            method=self.method,
            bins=self.bins,
            bin_bounds=self.bin_bounds,
            axis=self.axis,
            max_leaf_size=self.max_leaf_size,
            sah_block=int(self.sah_block),
        )

    def build_settings(self) -> dict:
        """What a tree depends on besides the geometry, by name (as state.BuiltTree.settings)."""
        return {"scope": self.scope, **self.build_config().tree_settings()}

    def render_options(self, *, viewport: bool = False) -> RenderOptions:
        """How this scene is traced, as the one typed object (bvhlab.RenderOptions) that F12, the
        sidebar's Render, Compare and the Rendered viewport all pass to the core: they cannot
        disagree. They differ in which switch shows the boxes: "Boxes in image" for the renders,
        "Show boxes" for the viewport (which traces n × n samples only once the view is still)."""
        show_boxes = self.overlay_show if viewport else self.render_overlay
        return RenderOptions(
            samples_per_axis=self.render_supersampling,
            max_depth=self.render_bounces,
            overlay_depth=(self.overlay_depth_min, self.overlay_depth_max) if show_boxes else None,
            color_by_depth=self.overlay_color_by_depth,
            line_color=tuple(self.overlay_color[:3]),
            line_width=self.overlay_line_width,
            overlay_level=self.overlay_level,
            traversal=self.traversal,
            mode=self.render_mode,
            traversal_counters=viewport and self.viewport_counter != "none",
            # Film ▸ Transparent: the alpha (the viewport draws premultiplied: its background shows)
            film_transparent=self.id_data.render.film_transparent,
        )


def _get_sphere(obj) -> bool:
    from bvhlab.blender import is_analytic_sphere

    return is_analytic_sphere(obj)


def _set_sphere(obj, value: bool) -> None:
    from bvhlab.blender import SPHERE_PROPERTY

    obj[SPHERE_PROPERTY] = bool(value)


def _sphere_changed(obj, _context) -> None:
    """The flag is read with the object's geometry: tagged so, the next sync reads the object again
    (a custom property changes nothing Blender evaluates, and a sync of moved objects alone kept it
    as it was: a flag set from a script took effect only at some later walk over the scene)."""
    obj.update_tag(refresh={"DATA"})


def _passes_changed(view_layer, _context) -> None:
    view_layer.update_render_passes()  # the compositor's Render Layers node shows the pass


def register_properties() -> None:
    bpy.types.Scene.bvhlab = bpy.props.PointerProperty(type=BVHLAB_PG_settings)
    # A pass switch lives on the view layer, like Blender's own (use_pass_z); the engine reads it.
    bpy.types.ViewLayer.bvhlab_use_pass_heatmap = BoolProperty(
        name="BVH Heatmap",
        default=False,  # as every diagnostic pass; with it, Traversal Auto walks the binary tree (Stack)
        update=_passes_changed,
        description="The bvhlab render engine's traversal-cost heatmap (box tests of the primary rays) as a pass",
    )
    bpy.types.ViewLayer.bvhlab_use_pass_counters = BoolProperty(
        name="BVH Counters",
        default=False,
        update=_passes_changed,
        description="The traversal counters of the primary rays (box tests, box hits, primitive tests, primitive "
        "hits, instance hits) as one float pass each, in raw counts per ray",
    )
    # Stored as the plain custom property bvhlab.blender reads, so files and the CLI need no add-on.
    bpy.types.Object.bvhlab_analytic_sphere = BoolProperty(
        name="Analytic sphere",
        get=_get_sphere,
        set=_set_sphere,
        update=_sphere_changed,
        description="Export this object as one exact sphere (centre and radius from its bounds)",
    )


def unregister_properties() -> None:
    del bpy.types.ViewLayer.bvhlab_use_pass_heatmap
    del bpy.types.ViewLayer.bvhlab_use_pass_counters
    del bpy.types.Object.bvhlab_analytic_sphere
    del bpy.types.Scene.bvhlab
