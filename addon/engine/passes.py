"""The engine's render passes: Combined, Depth (Blender's Z pass, when the view layer asks for it),
the traversal-cost heatmap as a pass of its own, and the traversal counters (issue 35: one float
pass per counter, raw counts per primary ray), so they can be saved (multilayer EXR) and
composited (Render Layers node)."""

from __future__ import annotations

import numpy as np

COMBINED, DEPTH, HEATMAP = "Combined", "Depth", "BVH Heatmap"
#: The view layer's switch for the heatmap pass (a property the add-on adds to ViewLayer).
HEATMAP_PROPERTY = "bvhlab_use_pass_heatmap"
#: The view layer's switch for the counter passes.
COUNTERS_PROPERTY = "bvhlab_use_pass_counters"


def counter_passes() -> dict[str, str]:
    """Counter name → its pass's name ("BVH Box Tests", ...), in the core's order."""
    from bvhlab.counters import COUNTERS, LABELS

    return {c: f"BVH {LABELS[c].title()}" for c in COUNTERS}


def counters_wanted(view_layer) -> bool:
    return bool(getattr(view_layer, COUNTERS_PROPERTY, False))


def heatmap_wanted(view_layer) -> bool:
    return bool(getattr(view_layer, HEATMAP_PROPERTY, False))


def wanted(view_layer) -> list[tuple[str, int, str, str]]:
    """(name, channels, channel ids, socket type) of each pass the view layer asks for."""
    passes = [(COMBINED, 4, "RGBA", "COLOR")]
    if view_layer.use_pass_z:
        passes.append((DEPTH, 1, "Z", "VALUE"))
    if heatmap_wanted(view_layer):
        passes.append((HEATMAP, 4, "RGBA", "COLOR"))
    if counters_wanted(view_layer):
        passes.extend((name, 1, "X", "VALUE") for name in counter_passes().values())
    return passes


def register(engine, scene, view_layer) -> None:
    """RenderEngine.update_render_passes: Blender allocates these in the Render Result and shows
    them as sockets of the compositor's Render Layers node."""
    for name, channels, ids, kind in wanted(view_layer):
        engine.register_pass(scene, view_layer, name, channels, ids, kind)


def write(layer, name: str, pixels: np.ndarray) -> bool:
    """Copy a top-row-first image (H, W) or (H, W, C) into a pass of a RenderLayer (Blender's row 0
    is the bottom). False when the layer has no such pass (the view layer did not ask for it)."""
    render_pass = layer.passes.get(name)
    if render_pass is None:
        return False
    render_pass.rect.foreach_set(np.ascontiguousarray(pixels[::-1], np.float32).reshape(-1))
    return True


def write_all(layer, images) -> None:
    """Combined, and Depth, the heatmap and the counters where the render made them (TraceImages),
    into a RenderLayer of the Render Result."""
    write(layer, COMBINED, images.color)
    if images.depth is not None:
        write(layer, DEPTH, images.depth)
    if images.heat is not None:
        write(layer, HEATMAP, images.heat)
    if images.counters is not None:
        for k, name in enumerate(counter_passes().values()):
            write(layer, name, images.counters[..., k])
