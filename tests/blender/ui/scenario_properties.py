"""UI scenario: every panel of the add-on open, in the 3D viewport's sidebar and in the Properties
editor at their default widths, holding what a user sees after Build, Compare, the sidebar's
Render, F12 and the Rendered viewport, on the bundled whitted scene with the engine. Checked on
the panels' own layouts (UILayout.introspect): no label or check box text is wider than its place
(tests/blender/ui/panel_layouts.py), the Compare table's Build column shows no 0 for a build that
took time. And: the sidebar's Render shows its image in an Image Editor (the default Layout has
none); Properties ▸ Last Render shows a finished F12 render and a new viewport frame with the mouse
elsewhere; a script setting the Rendered viewport's mode (Shade → Heatmap) gets a heatmap frame.

Blender runs this file (--python) and the driver (run_ui.py) imports it for `check`."""

from __future__ import annotations

SCENE = "whitted"
SCREENSHOTS: dict = {}
ENGINE = "BVHLAB_WHITTED"
#: Most seconds to wait for each thing.
SECONDS = {"render": 120, "viewport": 120, "heatmap": 30}


def steps(session):
    import importlib

    import bpy

    yield {"action": "key", "key": "Escape", "x": 800, "y": 450}  # the first-run splash
    yield 0.5
    module = session.install_zip()
    addon = importlib.import_module(module)
    names = _open_every_panel(module)
    import panel_layouts

    layouts = panel_layouts.record(names)
    scene, area = bpy.context.scene, session.view3d()
    scene.render.engine = ENGINE
    settings = scene.bvhlab
    settings.compare_frames, settings.compare_filepath = 1, str(session.shots / "compare.csv")
    properties = next(a for a in session.window().screen.areas if a.type == "PROPERTIES")
    properties.spaces.active.context = "RENDER"
    yield from session.show_sidebar_tab(area, "BVH")
    with session.override(area):
        assert bpy.ops.bvhlab.build() == {"FINISHED"}
        assert bpy.ops.bvhlab.compare() == {"FINISHED"}
    rows = addon.state.comparisons[addon.state.key(scene)]
    session.info["compare"] = [{"method": r["method"], "build_ms": r["build_ms"]} for r in rows]
    yield from _sidebar_render(session, addon, scene, area)
    yield from _final_render(session, module, scene, area, layouts)
    yield from _rendered_viewport(session, module, scene, area, layouts)
    yield from _counters(session, module, scene, area, layouts)
    properties.spaces.active.context = "VIEW_LAYER"  # the Passes panel
    yield 1.5
    properties.spaces.active.context = "RENDER"
    for window in list(bpy.context.window_manager.windows)[1:]:  # the render windows, over the panels
        with bpy.context.temp_override(window=window):
            bpy.ops.wm.window_close()
    yield 1.5
    yield {"action": "capture", "name": "panels"}
    session.info["layouts"] = dict(layouts)
    session.info["panels"] = names
    session.info["module"] = module


def _open_every_panel(module: str) -> list[str]:
    """The add-on's panels (names); those closed by default registered again open, as a user
    clicking their headers would have them (before any is drawn)."""
    import bpy

    panels = [c for c in bpy.types.Panel.__subclasses__() if c.__module__.startswith(module)]
    for panel in panels:
        if "DEFAULT_CLOSED" in getattr(panel, "bl_options", set()):
            bpy.utils.unregister_class(panel)
            panel.bl_options = set(panel.bl_options) - {"DEFAULT_CLOSED"}
            bpy.utils.register_class(panel)
    return sorted(p.__name__ for p in panels)


def _image_editors(image_name: str) -> list[str]:
    import bpy

    return [
        f"window {i}: {area.width} × {area.height}"
        for i, window in enumerate(bpy.context.window_manager.windows)
        for area in window.screen.areas
        if area.type == "IMAGE_EDITOR" and area.spaces.active.image and area.spaces.active.image.name == image_name
    ]


def _sidebar_render(session, addon, scene, area):
    """The sidebar's Render, pressed in the default Layout (no Image Editor anywhere)."""
    import bpy

    session.info["image_editors_before"] = _image_editors("BVH Render")
    with session.override(area, "UI"):
        assert bpy.ops.bvhlab.render() == {"FINISHED"}
    yield 2.0
    session.info["render_shown_in"] = _image_editors("BVH Render")
    session.info["render_message"] = addon.state.messages[addon.state.key(scene)][1]
    yield {"action": "capture", "name": "sidebar_render"}


def _final_render(session, module, scene, area, layouts):
    """F12 (a render job, as the key starts it); then nothing but waiting: Last Render must show
    it without the mouse moving over the Properties editor."""
    import importlib
    import time

    import bpy

    records = importlib.import_module(f"{module}.state")
    with session.override(area):
        bpy.ops.render.render("INVOKE_DEFAULT")
    yield from _until(lambda: records.last_final.get(records.key(scene)), SECONDS["render"], "the F12 render")
    yield from _until(lambda: not bpy.app.is_job_running("RENDER"), SECONDS["render"], "the end of the render job")
    done = time.monotonic()
    yield 2.0
    drawn = layouts.get("BVHLAB_PT_engine_status", {})
    size = records.last_final[records.key(scene)]["size"]
    session.info["last_render_redrawn"] = drawn.get("time", 0) > done
    session.info["last_render_texts"] = [i.get("draw_string") for i in _labels(drawn)]
    session.info["final_size"] = f"{size[0]} × {size[1]}"


def _rendered_viewport(session, module, scene, area, layouts):
    """Rendered shading until a full-resolution frame; Last Render shows it; then a script sets the
    mode to Heatmap and a heatmap frame must come (the viewport redrawn by itself)."""
    import importlib
    import time

    records = importlib.import_module(f"{module}.state")
    viewport = importlib.import_module(f"{module}.engine.viewport")
    area.spaces.active.shading.type = "RENDERED"
    key = records.key(scene)
    yield from _until(lambda: "full" in records.last_viewport.get(key, {}), SECONDS["viewport"], "a full frame")
    done = time.monotonic()
    yield 2.0
    drawn = layouts.get("BVHLAB_PT_engine_status", {})
    full = records.last_viewport[records.key(scene)]["full"]
    shown = " ".join(i.get("draw_string", "") for i in _labels(drawn))
    session.info["last_render_shows_viewport"] = drawn.get("time", 0) > done and f"{full['width']} × " in shown
    scene.bvhlab.render_mode = "heatmap"
    deadline = time.monotonic() + SECONDS["heatmap"]
    while time.monotonic() < deadline and not _frame_in_mode(viewport, "heatmap"):
        yield 0.2
    session.info["heatmap_frame"] = _frame_in_mode(viewport, "heatmap")
    yield {"action": "capture", "name": "heatmap"}


def _counters(session, module, scene, area, layouts):
    """A traversal counter chosen: the sidebar's Render Counter, and the Rendered viewport's frames
    counting it; then the Traversal Counters panel and Render Properties ▸ Viewport must draw
    their histograms (rows of bins and the percentiles)."""
    import importlib
    import time

    import bpy

    records = importlib.import_module(f"{module}.state")
    scene.bvhlab.render_mode = "shade"
    scene.bvhlab.viewport_counter = "box_tests"
    with session.override(area, "UI"):
        assert bpy.ops.bvhlab.render_counter() == {"FINISHED"}
    key = records.key(scene)

    def counted():
        with records.lock:
            return any(t.get("counter_histogram") is not None for t in records.last_viewport.get(key, {}).values())

    yield from _until(counted, SECONDS["viewport"], "a viewport frame counting box tests")
    done = time.monotonic()
    yield 2.0
    for name in ("BVHLAB_PT_counters", "BVHLAB_PT_engine_viewport"):
        drawn = layouts.get(name, {})
        session.info.setdefault("histogram_texts", {})[name] = {
            "redrawn": drawn.get("time", 0) > done,
            "texts": [i.get("draw_string", "") for i in _labels(drawn)],
        }
    yield {"action": "capture", "name": "counters"}


def _frame_in_mode(viewport, mode: str) -> bool:
    frames = [s.latest_frame() for s in list(viewport._sessions) if not s.closed]
    return any(f is not None and f.request.settings.mode == mode for f in frames)


def _labels(layout):
    import panel_layouts

    return [i for i in panel_layouts.walk(layout.get("tree", ())) if i.get("type") == panel_layouts.LABEL_TYPE]


def _until(condition, timeout: float, what: str):
    from session import until  # at run time, under Blender (the driver imports this file without bpy)

    return until(condition, timeout, what)


# -- checks, run by the driver (no bpy) --------------------------------------------------------
def check(shots: dict, info: dict) -> list[str]:
    """Assertion failures (empty when everything holds)."""
    import panel_layouts

    failures = []
    layouts = info["layouts"]
    undrawn = [n for n in info["panels"] if n not in layouts and n != "BVHLAB_PT_object"]
    if undrawn:
        failures.append(f"panels never drawn: {undrawn}")
    for name, layout in layouts.items():
        failures += panel_layouts.cut_off(name, layout)
    failures += _compare_build_column(layouts.get("BVHLAB_PT_compare"), info["compare"])
    if not info["render_shown_in"]:
        failures.append(f"the sidebar's Render shows its image nowhere: '{info['render_message']}'")
    if not (info["last_render_redrawn"] and info["final_size"] in " ".join(info["last_render_texts"])):
        failures.append(f"Last Render was not redrawn after F12 (it shows {info['last_render_texts']})")
    if not info["last_render_shows_viewport"]:
        failures.append("Last Render was not redrawn after the viewport's full frame")
    if not info["heatmap_frame"]:
        failures.append("render_mode = 'heatmap' set by a script brought no heatmap frame into the viewport")
    failures += _histograms(info["histogram_texts"])
    return failures


def _histograms(drawn: dict) -> list[str]:
    """Each counter panel drew a histogram after the counters came: its title (the counter and where
    from) and its percentiles line (the sidebar: the render's and the viewport's)."""
    expected = {"BVHLAB_PT_counters": ("Render", "Viewport"), "BVHLAB_PT_engine_viewport": ("Viewport",)}
    failures = []
    for name, sources in expected.items():
        texts = drawn[name]["texts"]
        # the title is two lines: the counter, then where from and how its range was chosen
        titles = [where for what, where in zip(texts, texts[1:]) if what == "Box tests"]
        for source in sources:
            if not any(t.startswith(f"{source}, ") and t.endswith(" range") for t in titles):
                failures.append(f"{name}: no histogram of the {source} drawn (labels {texts})")
        for line in ("p50 ", "p99 "):  # the percentiles, on two lines
            if sum(t.startswith(line) for t in texts) != len(sources):
                failures.append(f"{name}: {len(sources)} lines of {line.strip()} expected (labels {texts})")
        if not drawn[name]["redrawn"]:
            failures.append(f"{name} was not redrawn after the counters came")
    return failures


def _compare_build_column(layout, rows) -> list[str]:
    """Each method's Build cell, as drawn, is its build time to the precision shown, and no
    0 for a build that took time (the Build column of the table whose header has one)."""
    import panel_layouts

    if layout is None:
        return ["the Compare panel was never drawn"]
    cells, header, table = [], None, {}
    for split in (i for i in panel_layouts.walk(layout["tree"]) if i.get("type") == "LAYOUT_SPLIT"):
        cells = [i["draw_string"] for i in panel_layouts.walk(split.get("items", ())) if "draw_string" in i]
        if cells[:1] == ["Method"]:
            header = cells
        elif header and "Build" in header and len(cells) == len(header):
            table.setdefault(cells[0], cells[header.index("Build")])
    failures = []
    for row in rows:
        shown, built = table.get(row["method"]), row["build_ms"]
        if shown == "<0.01":
            right = built < 0.01
        else:
            right = shown is not None and float(shown) > 0 and abs(float(shown) - built) <= _half_unit(shown)
        if not right:
            failures.append(f"Compare: {row['method']} built in {built:.4f} ms, its Build cell says {shown}")
    return failures


def _half_unit(text: str) -> float:
    """Half of one unit in the last digit of a number as written ("0.35" → 0.005, "12" → 0.5)."""
    return 0.5 * 10.0 ** -(len(text.split(".")[1]) if "." in text else 0) + 1e-9


if __name__ == "__main__":
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).resolve().parent))
    import session as ui_session

    ui_session.run(steps)
