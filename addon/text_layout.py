"""Text that fits its panel: messages wrapped to the region's width instead of cut off, in the 3D
viewport's sidebar and in the Properties editor."""

from __future__ import annotations

#: Pixels (at UI scale 1) a panel takes from a label's width in the Properties editor: the panel's
#: margins and an icon (Blender 4.3 at 1600 × 900: a 247 px region fits a 184 px label).
PANEL_MARGIN_PX = 60
#: What the sidebar's category tabs take on top (a 291 px sidebar fits a 200 px label).
CATEGORY_TABS_PX = 30
#: What a box's margins take.
BOX_MARGIN_PX = 12


def wrap_text(text: str, max_width: float, measure) -> list[str]:
    """Words of `text` in lines no wider than `max_width` by `measure(str) -> px`; a word longer
    than a line is split between characters."""
    lines: list[str] = []
    line = ""
    for word in text.split():
        candidate = f"{line} {word}" if line else word
        if measure(candidate) <= max_width:
            line = candidate
            continue
        if line:
            lines.append(line)
        while measure(word) > max_width and len(word) > 1:
            cut = max(1, max(i for i in range(1, len(word) + 1) if measure(word[:i]) <= max_width or i == 1))
            lines.append(word[:cut])
            word = word[cut:]
        line = word
    if line:
        lines.append(line)
    return lines


def ui_text_measure(context):
    """measure(str) -> width in pixels of the UI's widget font at the current UI scale."""
    import blf

    preferences = context.preferences
    points = preferences.ui_styles[0].widget.points * preferences.system.ui_scale
    blf.size(0, points)
    return lambda text: blf.dimensions(0, text)[0]


def available_width(context, share: float = 1.0, in_box: bool = False) -> float:
    """Text width a label gets in the current region (the sidebar's or the Properties editor's),
    inside a box or not, in a column taking `share` of the panel's width."""
    scale = context.preferences.system.ui_scale
    margin = PANEL_MARGIN_PX + (CATEGORY_TABS_PX if context.region.type == "UI" else 0)
    margin += BOX_MARGIN_PX if in_box else 0
    return (context.region.width - margin * scale) * share


def wrapped_label(layout, context, text: str, icon: str = "NONE", share: float = 1.0, in_box: bool = False) -> None:
    """A label that wraps to the width `available_width` gives (the icon on the first line)."""
    col = layout.column(align=True)
    measure = ui_text_measure(context)
    for i, line in enumerate(wrap_text(text, available_width(context, share, in_box), measure)):
        col.label(text=line, icon=icon if i == 0 else "BLANK1")
