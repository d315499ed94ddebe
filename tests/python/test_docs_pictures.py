"""The README's sidebar picture shows what the code of the day draws: docs/panel.png carries (a PNG
text chunk that `make screenshots` writes, tests/blender/ui/scenario_panel.py) the scene, the
build settings and the numbers its panel drew, which that run checked against bvhlab.build; here
they must equal a build of the same scene with the same settings now, so a picture from older code
fails (issue 32: it showed 869 nodes where the code gives 865)."""

import json
import sys

import blender_checks  # noqa: F401
import harness

sys.path.insert(0, str(harness.ROOT / "tests" / "blender" / "ui"))
import scenario_panel  # noqa: E402
import xshot  # noqa: E402

PICTURE = harness.ROOT / "docs" / "panel.png"


def test_panel_picture_shows_the_stats_of_todays_build():
    import bpy

    import bvhlab
    from bvhlab.blender import export_scene

    carried = xshot.read_png_text(PICTURE)
    assert "bvhlab" in carried, f"{PICTURE} carries no record of what it shows: run `make screenshots`"
    shown = json.loads(carried["bvhlab"])
    harness.open_scene(shown["scene"])
    stats = bvhlab.build(export_scene(bpy.context, require_camera=False), **shown["build"]).stats
    now = {label: scenario_panel.number(stats[key]) for label, key in scenario_panel.STATS.items()}
    assert shown["drawn"] == now, f"{PICTURE} shows {shown['drawn']}, the code gives {now}: run `make screenshots`"
