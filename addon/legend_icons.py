"""Colour swatches for legends in panels (issue 35): the depth colours of the box overlay, the
stops of a counter's heat ramp and of a difference's diverging ramp, each a small icon filled with
the core's palette colour (bvhlab.palette), so the panel shows the very colours the overlay and the
images use."""

from __future__ import annotations

import numpy as np

#: Pixels per side of a swatch icon.
SWATCH_SIZE = 16
_previews = None


def swatch_icon(rgb) -> int:
    """icon_value of a swatch of linear colour `rgb` (made once per colour, kept until unregister)."""
    global _previews
    import bpy.utils.previews

    if _previews is None:
        _previews = bpy.utils.previews.new()
    c = np.clip(np.asarray(rgb, np.float32)[:3], 0.0, 1.0)
    key = "swatch_" + "_".join(f"{int(round(v * 1023))}" for v in c)
    preview = _previews.get(key)
    if preview is None:
        preview = _previews.new(key)
        preview.icon_size = (SWATCH_SIZE, SWATCH_SIZE)
        preview.icon_pixels_float = np.tile(np.append(c, 1.0), SWATCH_SIZE * SWATCH_SIZE).tolist()
    return preview.icon_id


def depth_legend(layout, depth_min: int, depth_max: int, most: int = 12) -> None:
    """Rows 'depth d' with its overlay colour for the shown depth range (the first `most` of it)."""
    from bvhlab import palette

    depths = list(range(depth_min, depth_max + 1))[:most]
    col = layout.column(align=True)
    for d, rgb in zip(depths, palette.depth(depths)):
        col.label(text=f"Depth {d}", icon_value=swatch_icon(rgb))
    if depth_max - depth_min + 1 > most:
        col.label(text=f"… to depth {depth_max}")


def _title(col, what: str, how: str) -> None:
    """The legend's title and, on a line of its own, how its range was chosen: two short lines fit
    the Properties editor's narrow column where one long one is cut."""
    col.label(text=what)
    if how:
        col.label(text=how)


def heat_legend(layout, lo: float, hi: float, what: str, how: str = "", stops: int = 5) -> None:
    """Rows of the heat ramp at `stops` values from lo (blue) to hi (red), each with its number."""
    from bvhlab import legend, palette

    col = layout.column(align=True)
    _title(col, what, how)
    values = np.linspace(lo, hi, stops)
    for v, rgb in zip(values, palette.heat(np.linspace(0.0, 1.0, stops))):
        prefix = "≥ " if v == hi else ""
        col.label(text=prefix + legend.number_text(round(float(v), 2)), icon_value=swatch_icon(rgb))


def diverging_legend(layout, span: float, what: str, how: str = "", stops: int = 5) -> None:
    """Rows of the diverging ramp (a difference's) at `stops` values from -span (blue) through 0
    (white) to span (red), each with its number."""
    from bvhlab import legend, palette

    col = layout.column(align=True)
    _title(col, what, how)
    values = np.linspace(-span, span, stops)
    for v, rgb in zip(values, palette.diverging(np.linspace(-1.0, 1.0, stops))):
        prefix = "≥ " if v == span else "≤ " if v == -span else ""
        col.label(text=prefix + legend.number_text(round(float(v), 2)), icon_value=swatch_icon(rgb))


def unregister() -> None:
    global _previews
    if _previews is not None:
        import bpy.utils.previews

        bpy.utils.previews.remove(_previews)
        _previews = None
