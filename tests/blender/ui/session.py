"""Runs a UI scenario inside a Blender window (imported by tests/blender/ui/scenario_*.py when
Blender runs them with --python). A scenario is a generator of steps: a number waits that many
seconds (the UI keeps drawing), a dict is a request to the driver (run_ui.py) — {"action":
"capture", "name": ...}, {"action": "key", "key": ...}, {"action": "scroll", "x", "y", "ctrl"} —
answered before the next step. At the end the scenario's `info` goes to result.json and Blender
quits; an exception is written there too and makes the exit code non-zero."""

from __future__ import annotations

import json
import sys
import time
import traceback
from pathlib import Path

import bpy


class Session:
    def __init__(self, shots: Path, zip_path: Path):
        self.shots, self.zip_path = shots, zip_path
        self.info: dict = {}
        self._serial = 0

    def request(self, **action) -> dict:
        self._serial += 1
        action["id"] = self._serial
        # written whole, then renamed: the driver polls for request-*.json and may read it at once
        path = self.shots / f"request-{self._serial:03d}.json"
        path.with_suffix(".tmp").write_text(json.dumps(action))
        path.with_suffix(".tmp").replace(path)
        return action

    def answered(self, action) -> bool:
        return (self.shots / f"done-{action['id']:03d}").exists()

    # -- what every scenario needs -------------------------------------------------------
    def window(self):
        return bpy.context.window_manager.windows[0]

    def view3d(self):
        """The largest 3D viewport area of the window."""
        areas = [a for a in self.window().screen.areas if a.type == "VIEW_3D"]
        return max(areas, key=lambda a: a.width * a.height)

    def region(self, area, kind: str):
        return next(r for r in area.regions if r.type == kind)

    def override(self, area=None, region_type: str = "WINDOW"):
        area = area or self.view3d()
        return bpy.context.temp_override(window=self.window(), area=area, region=self.region(area, region_type))

    def install_zip(self) -> str:
        with bpy.context.temp_override(window=self.window()):
            result = bpy.ops.extensions.package_install_files(
                filepath=str(self.zip_path), repo="user_default", enable_on_install=True
            )
        assert result == {"FINISHED"}, result
        return "bl_ext.user_default.bvhlab"

    def show_sidebar_tab(self, area, tab: str):
        """Steps that open the 3D viewport's sidebar on `tab`. Blender 4.x has the tab read-only:
        Ctrl+wheel over the tabs cycles them, as a user would."""
        from bvhlab.blender.compat import show_sidebar_tab

        area.spaces.active.show_region_ui = True
        sidebar = self.region(area, "UI")
        yield 1.0
        for _ in range(8):
            if sidebar.active_panel_category == tab or show_sidebar_tab(sidebar, tab):
                break
            rect = self.rect(sidebar)
            yield {"action": "scroll", "x": rect["x"] + rect["width"] - 8, "y": rect["y"] + 200, "ctrl": True}
            yield 0.5
        assert sidebar.active_panel_category == tab, sidebar.active_panel_category

    def rect(self, region) -> dict:
        """A region's rectangle in screen pixels, top-left origin (the window fills the screen)."""
        window = self.window()
        return {
            "x": region.x,
            "y": window.height - region.y - region.height,
            "width": region.width,
            "height": region.height,
        }


def until(condition, timeout: float, what: str):
    """Steps that wait, the UI drawing, until condition() holds; AssertionError after `timeout` s."""
    deadline = time.monotonic() + timeout
    while not condition():
        if time.monotonic() > deadline:
            raise AssertionError(f"no {what} within {timeout} s")
        yield 0.1


def run(steps, argv=None) -> None:
    """Start the scenario `steps(session)` from a timer; write result.json when it ends."""
    argv = sys.argv[sys.argv.index("--") + 1 :] if "--" in sys.argv else []
    shots, zip_path = Path(argv[argv.index("--shots") + 1]), Path(argv[argv.index("--zip") + 1])
    session = Session(shots, zip_path)
    generator = steps(session)
    pending = {"action": None, "since": time.time()}

    def finish(error: str | None) -> None:
        (shots / "result.json").write_text(json.dumps({"error": error, "info": session.info}, indent=1, default=str))
        bpy.ops.wm.quit_blender()

    def tick():
        if pending["action"] is not None:
            if not session.answered(pending["action"]):
                return 0.1
            pending["action"] = None
        try:
            step = next(generator)
        except StopIteration:
            finish(None)
            return None
        except Exception:
            finish(traceback.format_exc())
            return None
        if isinstance(step, dict):
            pending["action"] = session.request(**step)
            return 0.1
        return float(step)

    bpy.app.timers.register(tick, first_interval=1.0, persistent=True)
