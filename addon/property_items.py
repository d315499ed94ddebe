"""The items of the add-on's enum settings: the core's names (one definition, bvhlab._core) with
the label and tooltip a user reads in the UI, and the limits the settings derive from the core's."""

from __future__ import annotations

from bvhlab.build_config import AXES, BIN_BOUNDS, MAX_SAH_BLOCK, METHODS
from bvhlab.bvh import MAX_TREE_HEIGHT
from bvhlab.render import BACKENDS, MODES
from bvhlab.render_options import RENDER_TRAVERSALS
from bvhlab.update import UPDATE_POLICIES, UpdateConfig

# Names, defaults and limits come from the core (one definition, bvhlab._core); the add-on only
# adds what a user reads in the UI: a label and a tooltip per name.
_LABELS = {
    "median": ("Median", "Split at the median centroid: equal counts (report §2.3.1)"),
    "mean": ("Mean", "Split at the mean centroid (report §2.3.1)"),
    "midpoint": ("Midpoint", "Split the centroid bounds in half (PBRT's Middle)"),
    "sah": ("SAH (binned)", "Surface area heuristic over bins (report §2.3.2)"),
    "sweep_sah": ("SAH (full sweep)", "Exact surface area heuristic over every split"),
    "lbvh": ("LBVH", "Linear BVH from Morton codes"),
    "sbvh": ("SBVH", "Spatial splits (Stich et al. 2009): binned SAH, triangles clipped into repeated references"),
    "auto": ("Auto", "All three axes for the SAH methods, the largest centroid extent for the others"),
    "largest": ("Largest", "Split along the axis of largest centroid extent"),
    "random": ("Random", "Split along a random axis (seeded)"),
    "best": ("Best", "Try all three axes, keep the lowest SAH cost"),
    "box": ("Node box", "Equal buckets over the node's box: one pass over the references per node"),
    "centroids": ("Centroid bounds", "Equal buckets over the centroids' bounds (the report's, PBRT's)"),
    "stackless": ("Stackless", "Skip indices (report §3.1)"),
    "stack": ("Stack", "A stack, nearer child first (report §3.1); nodes as pairs of child boxes"),
    "wide": (
        "Wide (CPU)",
        "The CPU tracer only (Auto renders it there): each ray through an 8-wide copy of the tree, the "
        "image of Stack about twice as fast; its heatmap counts 8 box tests a wide node, no other counters",
    ),
    "shade": ("Shade", "Whitted shading"),
    "heatmap": ("Heatmap", "Box tests per pixel"),
    "vulkan": ("Vulkan", "Vulkan compute tracer"),
    "cpu": ("CPU", "C++ reference tracer"),
}
_TRAVERSAL_AUTO = (
    "Auto",
    "The fastest walk of the device that renders: Wide on the CPU, Stack on a GPU; Stack wherever a "
    "count of the walk is shown (the heatmap, its pass, the counters). The same image",
)
_BACKEND_AUTO = (
    "Auto",
    "A Vulkan GPU when there is one, otherwise the CPU reference tracer (also instead of a CPU "
    "Vulkan driver such as lavapipe, where it is faster)",
)


def _measure_items() -> list[tuple[str, str, str]]:
    from bvhlab.inspect.measures import MEASURES

    return [("depth", "Depth", "The depth colours, or the line colour (above)")] + [
        (name, label, tooltip) for name, (label, tooltip) in MEASURES.items()
    ]


def _items(names) -> list[tuple[str, str, str]]:
    """EnumProperty items for the core's names, labelled for the UI."""
    return [(n, *_LABELS.get(n, (n.replace("_", " ").title(), ""))) for n in names]


def _counter_items() -> list[tuple[str, str, str]]:
    from bvhlab.counters import COUNTERS, LABELS

    from .engine.counter_view import NO_COUNTER

    shaded = (NO_COUNTER, "Shading", "The render mode's image")
    per_ray = "per primary ray (its closest-hit walk; averaged over the samples)"
    return [shaded, *((c, LABELS[c], f"{LABELS[c]} {per_ray}, blue few, red many") for c in COUNTERS)]


def _two_tree_items() -> list[tuple[str, str, str]]:
    from .ops_compare import COMPARE_METHODS

    return [
        (method, label, f"The tree of {label}, built as Compare Methods builds it") for label, method in COMPARE_METHODS
    ]


COUNTER_ITEMS = _counter_items()
TWO_TREE_ITEMS = _two_tree_items()
MEASURE_ITEMS = _measure_items()
METHOD_ITEMS = _items(METHODS)
# (module level: Blender evaluates the annotations below in a scope where a comprehension could
# not see this module's names)
BACKEND_ITEMS = [(b, *(_BACKEND_AUTO if b == "auto" else _LABELS[b])) for b in BACKENDS]
AXIS_ITEMS = _items(AXES)
# Numbered as before Auto came (a .blend stores an enum's number: one saved with Stackless must
# load as Stackless), Auto listed first.
TRAVERSAL_ITEMS = [
    (t, *(_TRAVERSAL_AUTO if t == "auto" else _LABELS[t]), (*RENDER_TRAVERSALS[1:], "auto").index(t))
    for t in RENDER_TRAVERSALS
]
MODE_ITEMS = _items(MODES)
BIN_BOUNDS_ITEMS = _items(BIN_BOUNDS)
#: The SAH's block sizes, the powers of two up to the core's limit (a string per item, as an
#: EnumProperty needs; build_config passes the int).
SAH_BLOCK_ITEMS = [
    (str(1 << k), str(1 << k), "Primitives one by one (the report's SAH)" if k == 0 else f"Blocks of {1 << k}")
    for k in range(MAX_SAH_BLOCK.bit_length())
]
OVERLAY_LEVEL_ITEMS = [
    ("tlas", "TLAS", "The top-level tree's boxes (its leaves: the instances' world boxes)"),
    ("blas", "BLAS", "Each mesh's tree's boxes, moved into the world by each of its instances"),
    ("both", "Both", "The TLAS's and the BLASes' boxes"),
]
_POLICY_LABELS = {
    "rebuild": ("Rebuild", "A fresh build of the mesh's tree"),
    "refit": ("Refit", "Boxes only: the topology stays, its SAH cost may grow"),
    "partial": ("Partial", "Refit, then rebuild the subtrees whose SAH cost grew (Yoon et al. 2007)"),
    "adaptive": ("Adaptive", "Refit, then rebuild where or when the measured SAH cost calls for it"),
}
UPDATE_POLICY_ITEMS = [(p, *_POLICY_LABELS.get(p, (p.title(), ""))) for p in UPDATE_POLICIES]
DEFAULT_UPDATE_POLICY = UpdateConfig().policy
#: The maximum node depth any tree can have.
MAX_DEPTH = MAX_TREE_HEIGHT - 1
