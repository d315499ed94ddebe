"""What the add-on's panels draw, recorded inside Blender (the layout of every draw by
UILayout.introspect, the width of each text in the UI font, the region's width) and checked by the
driver (numpy-free, bpy-free): no label or check box text wider than the place it gets at the
region's width, modelled on how Blender shares a width out (rows and splits between their items,
boxes take a margin)."""

from __future__ import annotations

import time

LABEL_TYPE, CHECKBOX_TYPE, DECORATOR_TYPE = 10240, 6656, 29696  # UI_BTYPE_* in UILayout.introspect()
#: Pixels (at UI scale 1) a region takes from a text's width: panel margins and an icon (every text
#: is assumed to have one; a check box's box is that icon), measured on Blender 4.3's screen at
#: 1600 × 900 with labels of known widths: the Properties editor's 247 px fit a 184 px label, not a
#: 198 px one; the sidebar's 291 px (category tabs too) fit 200 px, not 216 px.
INSETS = {"PROPERTIES": 60, "VIEW_3D": 90}
#: What a box's margins take; a property's decorator column; the share of a split's first column
#: (Blender's property split, 0.4, which the panels use for their own splits too).
BOX_INSET, DECORATOR, SPLIT_FIRST = 12, 20, 0.4


def record(panel_names) -> dict:
    """Hook every named panel's draw: keep, per panel, its latest layout tree, the width of each
    of its texts in the UI font (blf measures correctly only in a drawing window), the region's
    width and kind, and when it was drawn (time.monotonic)."""
    import blf
    import bpy

    layouts: dict = {}

    def hook(panel, context):
        system = context.preferences.system
        blf.size(0, context.preferences.ui_styles[0].widget.points * system.ui_scale)
        tree = panel.layout.introspect()
        texts = sorted({item.get("draw_string", "") for item in walk(tree) if item.get("type") in _TEXT_TYPES})
        layouts[type(panel).__name__] = {
            "tree": tree,
            "scale": system.ui_scale,
            "region": context.region.width,
            "editor": context.area.type,
            "widths": {t: blf.dimensions(0, t)[0] for t in texts},
            "time": time.monotonic(),
        }

    for name in panel_names:
        getattr(bpy.types, name).append(hook)
    return layouts


_TEXT_TYPES = (LABEL_TYPE, CHECKBOX_TYPE)


def walk(items):
    for item in items:
        yield item
        yield from walk(item.get("items", ()))


def texts(layout) -> list[str]:
    """Every label's text, in drawing order."""
    return [i["draw_string"] for i in walk(layout["tree"]) if i.get("type") == LABEL_TYPE]


def _is_decorator(item) -> bool:
    leaves = [i for i in walk([item]) if not i.get("items")]
    return bool(leaves) and all(i.get("type") == DECORATOR_TYPE for i in leaves)


def cut_off(name: str, layout) -> list[str]:
    """Labels and check box texts wider than the width their container gets at the region's width."""
    scale = layout["scale"]
    failures = []

    def visit(items, width):
        for item in items:
            kind = item.get("type")
            if kind in _TEXT_TYPES:
                needed = layout["widths"].get(item["draw_string"], 0)
                if needed > width:
                    failures.append(f"{name}: '{item['draw_string']}' needs {needed:.0f} px, its place {width:.0f} px")
            children = item.get("items", ())
            if kind == "LAYOUT_SPLIT" and len(children) > 1:
                visit(children[:1], width * SPLIT_FIRST)
                visit(children[1:], width * (1 - SPLIT_FIRST) / (len(children) - 1))
            elif kind == "LAYOUT_ROW" and children:
                decorators = [c for c in children if _is_decorator(c)]
                others = [c for c in children if not _is_decorator(c)]
                visit(others, (width - DECORATOR * scale * len(decorators)) / max(len(others), 1))
            elif kind == "LAYOUT_BOX":
                visit(children, width - BOX_INSET * scale)
            else:
                visit(children, width)

    visit(layout["tree"], layout["region"] - INSETS[layout["editor"]] * scale)
    return failures
