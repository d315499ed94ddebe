"""Text that fits the sidebar: messages wrapped to the region's width instead of cut off."""

from __future__ import annotations

#: Pixels the sidebar takes from a label (at UI scale 1): category tabs, panel margins, an icon.
PANEL_MARGIN_PX = 90


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


def available_width(context) -> float:
    """Text width a label gets in the current sidebar region."""
    scale = context.preferences.system.ui_scale
    return context.region.width - PANEL_MARGIN_PX * scale


def wrapped_label(layout, context, text: str, icon: str = "NONE") -> None:
    """A label that wraps to the region's width (the icon on the first line)."""
    col = layout.column(align=True)
    measure = ui_text_measure(context)
    for i, line in enumerate(wrap_text(text, available_width(context), measure)):
        col.label(text=line, icon=icon if i == 0 else "BLANK1")
