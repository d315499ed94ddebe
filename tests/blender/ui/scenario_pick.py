"""UI scenario: Pick Box as a user runs it (issue 35). Build on the bundled whitted scene, show the
boxes of depth 2, start Pick Box (INVOKE_DEFAULT, as the button does) and click with the mouse
(xdotool) at three points of the 3D viewport. Checked: each click picks what bvhlab.inspect.pick
gives for the ray through that pixel (from Blender's own region_2d_to_* functions); the picked box
is drawn in white (the screenshot has white pixels it did not have before the pick); clicks in the
timeline and in the sidebar reach them and keep the pick; Esc leaves the mode, after which a click
picks nothing new.

Blender runs this file (--python) and the driver (run_ui.py) imports it for `check`."""

from __future__ import annotations

SCENE = "whitted"
SCREENSHOTS: dict = {}
#: The clicks, as fractions of the viewport region (x from the left, y from the bottom).
CLICKS = ((0.5, 0.5), (0.35, 0.4), (0.62, 0.55))
WHITE = 250  # a highlight pixel: every channel at least this


def steps(session):
    import bpy

    yield {"action": "key", "key": "Escape", "x": 800, "y": 450}  # the first-run splash
    yield 0.5
    module = session.install_zip()
    import importlib

    from bpy_extras import view3d_utils

    from bvhlab.inspect.pick import pick

    state = importlib.import_module(f"{module}.state")
    area = session.view3d()
    area.spaces.active.overlay.show_overlays = True
    region = session.region(area, "WINDOW")
    view = area.spaces.active.region_3d
    scene = bpy.context.scene
    with session.override(area):
        assert bpy.ops.bvhlab.build() == {"FINISHED"}
    scene.bvhlab.overlay_depth_min, scene.bvhlab.overlay_depth_max = 2, 2
    scene.bvhlab.overlay_color_by_depth = True
    yield 1.0
    yield {"action": "capture", "name": "before"}
    with session.override(area):
        started = bpy.ops.bvhlab.pick_box("INVOKE_DEFAULT")
    session.info["started"] = sorted(started)
    rect = session.rect(region)
    tree = state.tree_for(scene)
    session.info["clicks"] = []
    for i, (fx, fy) in enumerate(CLICKS):
        rx, ry = int(fx * region.width), int(fy * region.height)
        origin = view3d_utils.region_2d_to_origin_3d(region, view, (rx, ry))
        direction = view3d_utils.region_2d_to_vector_3d(region, view, (rx, ry))
        expected = pick(tree.bvh, origin, direction, (2, 2)).node
        yield {"action": "click", "x": rect["x"] + rx, "y": rect["y"] + region.height - 1 - ry}
        yield 1.0
        session.info["clicks"].append({"expected": expected, "picked": state.picked_node(scene)})
        if i == 0:
            yield {"action": "capture", "name": "picked"}
    # clicks outside the viewport's own drawing go to Blender, not to the pick (each click of the
    # window was once taken as a pick through the viewport's projection: helper probe): the
    # timeline, another area, takes its frame; a click in the sidebar, drawn over the view, keeps it
    rx, ry = int(CLICKS[0][0] * region.width), int(CLICKS[0][1] * region.height)  # a pick to keep
    yield {"action": "click", "x": rect["x"] + rx, "y": rect["y"] + region.height - 1 - ry}
    yield 1.0
    kept, frame = state.picked_node(scene), scene.frame_current
    timeline = next(a for a in session.window().screen.areas if a.type == "DOPESHEET_EDITOR")
    strip = session.rect(session.region(timeline, "WINDOW"))
    yield {"action": "click", "x": strip["x"] + int(0.7 * strip["width"]), "y": strip["y"] + strip["height"] // 2}
    yield 1.0
    area.spaces.active.show_region_ui = True
    yield 1.0
    sidebar = session.rect(session.region(area, "UI"))
    yield {"action": "click", "x": sidebar["x"] + sidebar["width"] // 2, "y": sidebar["y"] + sidebar["height"] - 30}
    yield 1.0
    session.info["outside"] = {
        "kept": kept,
        "after": state.picked_node(scene),
        "frame": frame,
        "frame_after": scene.frame_current,
    }
    yield {"action": "key", "key": "Escape", "x": rect["x"] + 20, "y": rect["y"] + 40}
    yield 0.5
    before_last = state.picked_node(scene)
    rx, ry = int(0.5 * region.width), int(0.5 * region.height)
    yield {"action": "click", "x": rect["x"] + rx, "y": rect["y"] + region.height - 1 - ry}
    yield 1.0
    session.info["after_esc"] = {"before": before_last, "after": state.picked_node(scene)}
    session.info["region"] = rect


# -- checks, run by the driver (no bpy) --------------------------------------------------------
def check(shots: dict, info: dict) -> list[str]:
    failures = []
    if info.get("started") != ["RUNNING_MODAL"]:
        failures.append(f"Pick Box started {info.get('started')}, not modal")
    clicks = info.get("clicks", [])
    if len(clicks) != 3:
        failures.append(f"{len(clicks)} clicks recorded of 3")
    for click in clicks:
        if click["picked"] != click["expected"]:
            failures.append(f"a click picked {click['picked']}, the ray through its pixel {click['expected']}")
    if not any(c["expected"] is not None for c in clicks):
        failures.append("no click was on a box: the scenario's clicks miss the scene")
    outside = info.get("outside", {})
    if outside.get("kept") is None or outside.get("after") != outside.get("kept"):
        failures.append(f"a click outside the viewport changed the pick (or none was kept): {outside}")
    if outside.get("frame_after") == outside.get("frame"):
        failures.append(f"a click in the timeline did not reach it while Pick Box ran: {outside}")
    after = info.get("after_esc", {})
    if after.get("before") != after.get("after"):
        failures.append(f"a click after Esc still picked: {after}")
    if "before" in shots and "picked" in shots and "region" in info:
        r = info["region"]
        crop = [
            shot[r["y"] : r["y"] + r["height"], r["x"] : r["x"] + r["width"], :3]
            for shot in (shots["before"], shots["picked"])
        ]
        white = [int((c.min(-1) >= WHITE).sum()) for c in crop]
        info["white_pixels"] = white
        if clicks and clicks[0]["picked"] is not None and white[1] < white[0] + 100:
            failures.append(f"the picked box is not drawn in white: {white[0]} white pixels before, {white[1]} after")
    return failures


if __name__ == "__main__":
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).resolve().parent))
    import session as ui_session

    ui_session.run(steps)
