"""UI scenario: the sidebar's BVH tab in a real Blender window on the bundled whitted scene.
Install the zip, open the sidebar and its BVH tab, press Build (the overlay must come on by
itself), and capture the screen with and without the boxes. Checked on the pictures: the panel
region is not blank, box lines of each depth of the default range 0-3 are drawn over the viewport;
and on the panel's own layout (UILayout.introspect): every stat is a label | value row, the values
those of bvhlab.build on the same scene and settings (the picture `make screenshots` keeps carries
them: tests/python/test_docs_pictures.py), and no label is wider than the space it gets at the
default sidebar width.

Blender runs this file (--python) and the driver (run_ui.py) imports it for `check`."""

from __future__ import annotations

SCENE = "whitted"
#: Pictures `make screenshots` copies into docs/: shot name → file name.
SCREENSHOTS = {"panel": "panel.png"}
PANELS = ("BVHLAB_PT_main", "BVHLAB_PT_overlay", "BVHLAB_PT_render", "BVHLAB_PT_object")
#: The statistics the panel shows that a build of the same scene and settings reproduces exactly
#: (the panel's label → bvh.stats' key); the build time differs between builds.
STATS = {"Primitives": "primitives", "Nodes": "nodes", "Leaves": "leaves", "Height": "height", "SAH cost": "sah_cost"}


def steps(session):
    import bpy

    yield {"action": "key", "key": "Escape", "x": 800, "y": 450}  # the first-run splash
    yield 0.5
    module = session.install_zip()
    area = session.view3d()
    area.spaces.active.region_3d.view_perspective = "CAMERA"
    sidebar = session.region(area, "UI")
    yield from session.show_sidebar_tab(area, "BVH")
    import panel_layouts

    layouts = panel_layouts.record(PANELS)
    with session.override(area):
        assert bpy.ops.bvhlab.build() == {"FINISHED"}
    settings = bpy.context.scene.bvhlab
    session.info["overlay_after_build"] = settings.overlay_show
    session.info["depth_range"] = [settings.overlay_depth_min, settings.overlay_depth_max]
    session.info["built"] = _direct_build(settings)
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


def _direct_build(settings) -> dict:
    """The scene, the build settings and the stats of bvhlab.build on the scene exported directly
    (not through the add-on): what the panel must show."""
    import bpy

    import bvhlab
    from bvhlab.blender import export_scene

    config = settings.build_config()
    stats = bvhlab.build(export_scene(bpy.context, require_camera=False), config=config).stats
    return {"scene": SCENE, "build": config.tree_settings(), "stats": {k: stats[k] for k in STATS.values()}}


# -- checks, run by the driver on the captured pictures (numpy only, no bpy) ---------------------
def check(shots: dict, info: dict) -> list[str]:
    """Assertion failures (empty when everything holds)."""
    import numpy as np
    import panel_layouts

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
    failures += _stats_rows(info["layouts"].get("BVHLAB_PT_main"), info["built"])
    for name, layout in info["layouts"].items():
        failures += panel_layouts.cut_off(name, layout)
    return failures


def screenshot_text(info: dict) -> dict[str, str]:
    """What docs/panel.png carries besides its pixels: the scene, the build settings, the stats of
    the build and the numbers the panel drew (tests/python/test_docs_pictures.py reads them)."""
    import json

    return {"bvhlab": json.dumps(info["built"], sort_keys=True)}


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


def number(value) -> str:
    return f"{value:,}" if isinstance(value, int) else f"{value:.2f}"


def _stats_rows(layout, built: dict) -> list[str]:
    """The stats box: each statistic a split of exactly two labels, label | value, the value that of
    bvhlab.build on the same scene and settings (so `make screenshots` cannot write a picture of
    other numbers). The numbers drawn go into the picture (a PNG text chunk) for
    tests/python/test_docs_pictures.py to check against the build of the day."""
    import panel_layouts

    if layout is None:
        return ["the BVH panel was never drawn"]
    splits = [item for item in panel_layouts.walk(layout["tree"]) if item.get("type") == "LAYOUT_SPLIT"]
    rows = [[i.get("draw_string") for i in s.get("items", ())] for s in splits]
    drawn = {row[0]: row[1] for row in rows if len(row) == 2}
    missing = [label for label in (*STATS, "Build") if label not in drawn]
    if missing:
        return [f"stats not shown as label | value rows: {missing} missing in {rows}"]
    expected = {label: number(built["stats"][key]) for label, key in STATS.items()}
    wrong = {label: (drawn[label], expected[label]) for label in STATS if drawn[label] != expected[label]}
    built["drawn"] = {label: drawn[label] for label in STATS}
    return [f"the panel's stats are not those of bvhlab.build (drawn, built): {wrong}"] if wrong else []


if __name__ == "__main__":
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).resolve().parent))
    import session as ui_session

    ui_session.run(steps)
