"""UI scenario: the sidebar's BVH tab in a real Blender window on the bundled whitted scene.
Install the zip, open the sidebar and its BVH tab, press Build (the overlay must come on by
itself), and capture the screen with and without the boxes. Checked on the pictures: the panel
region is not blank, box lines of each depth of the default range 0-3 are drawn over the viewport;
and on the panel's own layout (UILayout.introspect): every stat is a label | value row and no
label is wider than the space it gets at the default sidebar width.

Blender runs this file (--python) and the driver (run_ui.py) imports it for `check`."""

from __future__ import annotations

SCENE = "whitted"
#: Pictures `make screenshots` copies into docs/: shot name → file name.
SCREENSHOTS = {"panel": "panel.png"}
PANELS = ("BVHLAB_PT_main", "BVHLAB_PT_overlay", "BVHLAB_PT_render", "BVHLAB_PT_object")
LABEL_TYPE = 10240  # UI_BTYPE_LABEL in UILayout.introspect()
#: Pixels (at UI scale 1) the sidebar takes from a label's width: category tabs, panel margins and an
#: icon (every label is assumed to have one), measured on Blender 4.3's screen; what a box's margins
#: and a property's decorator column take; the share of a split's first column (Blender's property
#: split, 0.4, the narrowest the panels use).
SIDEBAR_INSET, BOX_INSET, DECORATOR, SPLIT_FIRST = 90, 12, 20, 0.4
DECORATOR_TYPE = 29696


def steps(session):
    import bpy

    yield {"action": "key", "key": "Escape", "x": 800, "y": 450}  # the first-run splash
    yield 0.5
    module = session.install_zip()
    from bvhlab.blender.compat import show_sidebar_tab

    area = session.view3d()
    area.spaces.active.show_region_ui = True
    area.spaces.active.region_3d.view_perspective = "CAMERA"
    sidebar = session.region(area, "UI")
    yield 1.0
    for _ in range(8):  # 4.x: the tab is read-only; Ctrl+wheel over the tabs cycles them, as a user would
        if sidebar.active_panel_category == "BVH" or show_sidebar_tab(sidebar, "BVH"):
            break
        rect = session.rect(sidebar)
        yield {"action": "scroll", "x": rect["x"] + rect["width"] - 8, "y": rect["y"] + 200, "ctrl": True}
        yield 0.5
    assert sidebar.active_panel_category == "BVH", sidebar.active_panel_category
    layouts = _record_layouts(session)
    with session.override(area):
        assert bpy.ops.bvhlab.build() == {"FINISHED"}
    settings = bpy.context.scene.bvhlab
    session.info["overlay_after_build"] = settings.overlay_show
    session.info["depth_range"] = [settings.overlay_depth_min, settings.overlay_depth_max]
    area.tag_redraw()
    yield 1.5
    yield {"action": "capture", "name": "panel"}
    session.info["layouts"] = dict(layouts)
    settings.overlay_show = False
    area.tag_redraw()
    yield 1.5
    yield {"action": "capture", "name": "no_overlay"}
    import numpy as np

    from bvhlab._core import depth_colors

    session.info["palette"] = depth_colors(np.arange(4, dtype=np.uint32)).tolist()
    session.info["sidebar"], session.info["viewport"] = (
        session.rect(sidebar),
        session.rect(session.region(area, "WINDOW")),
    )
    session.info["area"] = {
        "x": area.x,
        "y": session.window().height - area.y - area.height,
        "width": area.width,
        "height": area.height,
    }
    session.info["module"] = module


def _record_layouts(session) -> dict:
    """Hook every bvhlab panel's draw: keep its layout tree and the pixel width of each label
    text in the UI font, as drawn (blf measures correctly only in a drawing window)."""
    import blf
    import bpy

    layouts: dict = {}

    def hook(panel, context):
        system = context.preferences.system
        blf.size(0, context.preferences.ui_styles[0].widget.points * system.ui_scale)
        tree = panel.layout.introspect()
        texts = sorted({item["draw_string"] for item in _walk(tree) if item.get("type") == LABEL_TYPE})
        layouts[type(panel).__name__] = {
            "tree": tree,
            "scale": system.ui_scale,
            "region": context.region.width,
            "widths": {t: blf.dimensions(0, t)[0] for t in texts},
        }

    for name in PANELS:
        getattr(bpy.types, name).append(hook)
    return layouts


def _walk(items):
    for item in items:
        yield item
        yield from _walk(item.get("items", ()))


# -- checks, run by the driver on the captured pictures (numpy only, no bpy) ---------------------
def check(shots: dict, info: dict) -> list[str]:
    """Assertion failures (empty when everything holds)."""
    import numpy as np

    failures = []
    if not info.get("overlay_after_build"):
        failures.append("the overlay is off after Build")
    panel, bare = shots["panel"].astype(np.int32), shots["no_overlay"].astype(np.int32)
    side = _crop(panel, info["sidebar"])
    background = np.median(side.reshape(-1, 3), 0)
    inked = (np.abs(side - background).max(-1) > 40).mean()
    colours = len(np.unique(side.reshape(-1, 3), axis=0))
    if inked < 0.03 or colours < 20:
        failures.append(f"the sidebar looks blank: {inked:.3f} of it differs from its background, {colours} colours")
    view, view_bare = _crop(panel, info["viewport"]), _crop(bare, info["viewport"])
    changed = np.abs(view - view_bare).max(-1) > 30
    counts = _pixels_per_depth(view[changed], np.array(info["palette"]))
    info["box_pixels_per_depth"] = counts
    if changed.sum() < 500:
        failures.append(f"only {changed.sum()} viewport pixels change when the boxes are shown")
    if min(counts) < 20:
        failures.append(f"not every depth of the range shows in its colour: pixels per depth {counts}")
    failures += _stats_rows(info["layouts"].get("BVHLAB_PT_main"))
    for name, layout in info["layouts"].items():
        failures += _cut_off_labels(name, layout)
    return failures


def _crop(image, rect):
    return image[rect["y"] : rect["y"] + rect["height"], rect["x"] : rect["x"] + rect["width"]]


def _pixels_per_depth(pixels, palette_linear) -> list[int]:
    """Changed pixels whose colour is (display-encoded) one depth's palette colour."""
    import numpy as np

    srgb = np.where(palette_linear <= 0.0031308, palette_linear * 12.92, 1.055 * palette_linear ** (1 / 2.4) - 0.055)
    counts = []
    for linear, display in zip(palette_linear * 255, srgb * 255):
        near = [np.abs(pixels - c).max(-1) < 24 for c in (linear, display)]
        counts.append(int(max(n.sum() for n in near)))
    return counts


def _stats_rows(layout) -> list[str]:
    """The stats box: each statistic a split of exactly two labels, label | value."""
    if layout is None:
        return ["the BVH panel was never drawn"]
    splits = [item for item in _walk(layout["tree"]) if item.get("type") == "LAYOUT_SPLIT"]
    rows = [[i.get("draw_string") for i in s.get("items", ())] for s in splits]
    labelled = {row[0] for row in rows if len(row) == 2}
    missing = [
        label for label in ("Primitives", "Nodes", "Leaves", "Height", "SAH cost", "Build") if label not in labelled
    ]
    return [f"stats not shown as label | value rows: {missing} missing in {rows}"] if missing else []


def _is_decorator(item) -> bool:
    leaves = [i for i in _walk([item]) if not i.get("items")]
    return bool(leaves) and all(i.get("type") == DECORATOR_TYPE for i in leaves)


def _cut_off_labels(name: str, layout) -> list[str]:
    """Labels wider than the width their container gets at this sidebar width (rows and splits
    share it between their items, boxes take a margin)."""
    scale = layout["scale"]
    failures = []

    def visit(items, width):
        for item in items:
            kind = item.get("type")
            if kind == LABEL_TYPE and layout["widths"].get(item["draw_string"], 0) > width:
                failures.append(
                    f"{name}: label '{item['draw_string']}' is {layout['widths'][item['draw_string']]:.0f} px, "
                    f"its place {width:.0f} px"
                )
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

    visit(layout["tree"], layout["region"] - SIDEBAR_INSET * scale)
    return failures


if __name__ == "__main__":
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).resolve().parent))
    import session as ui_session

    ui_session.run(steps)
