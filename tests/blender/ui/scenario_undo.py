"""UI scenario: undo and redo under the Rendered viewport. On the bundled whitted scene, Rendered
shading with bvhlab's engine, a user moves a sphere (G), deletes it (X), gives it an Array
modifier of 3 (a new triangle count), moves its vertices in Edit Mode, each with an undo step,
and undoes and redoes each:
Blender re-reads the changed data blocks from its undo memory and names them to the engine in its
own way (view_update), which the viewport's LiveScene must follow, placing or walking. Checked
after every step: the scene the viewport traces is the scene a fresh export reads (both rendered
by bvhlab.render from the scene camera, their pixels compared), and the step changed what it
should (the moved, deleted or subdivided picture differs from the first).

Blender runs this file (--python) and the driver (run_ui.py) imports it for `check`."""

from __future__ import annotations

SCENE = "whitted"
SCREENSHOTS: dict = {}
ENGINE = "BVHLAB_WHITTED"
#: Rendered for the comparison (the scene camera's aspect need not be kept: both images alike).
SIZE = (96, 72)
#: A pixel differs where a channel differs by more than this; a step fails where more than
#: SHARE of the pixels differ (an instance's transform against the same triangles in the world
#: moves a grazing hit or two).
PIXEL, SHARE = 0.02, 0.003
#: The steps: (name, whether its picture must differ from the first).
EXPECTED = (
    ("start", False),
    ("moved", True),
    ("move undone", False),
    ("move redone", True),
    ("move undone again", False),
    ("deleted", True),
    ("delete undone", False),
    ("arrayed", True),
    ("array undone", False),
    ("array redone", True),
    ("edited in edit mode", True),
    ("edit undone in edit mode", True),  # the array is still there
    ("edit redone, object mode", True),
)


def steps(session):
    import bpy

    yield {"action": "key", "key": "Escape", "x": 800, "y": 450}  # the first-run splash
    yield 0.5
    module = session.install_zip()
    import importlib

    viewport = importlib.import_module(f"{module}.engine.viewport")
    scene, area = bpy.context.scene, session.view3d()  # (scene: before any undo only)
    scene.render.engine = ENGINE
    scene.bvhlab.backend, scene.bvhlab.render_supersampling = "cpu", 1
    scene.bvhlab.light_distance = 6.0  # fixed: a fresh export of a changed scene is lit alike
    area.spaces.active.shading.type = "RENDERED"
    with session.override(area):  # the settings above are where the first undo returns to
        bpy.ops.ed.undo_push(message="bvhlab settings")
    yield from _until(lambda: _traced(viewport) is not None, 120, "the viewport's first scene")
    first = _render(_traced(viewport))
    session.info["steps"] = []

    def compare(name: str):
        yield 1.5  # Blender calls view_update when it redraws the viewport after the change
        traced = _traced(viewport)
        session.info["steps"].append(_compared(name, traced, first))

    def operator(call, **kwargs):
        """`call` as a user's click runs it: with its undo step (bpy.ops pushes none unless asked)."""
        with session.override(area):
            result = call("EXEC_DEFAULT", True, **kwargs)
        assert result == {"FINISHED"}, (call, result)

    # after an undo every Python reference to Blender data may be stale (the blocks are read again
    # from the undo memory): objects and the scene are looked up by name at each use
    def select(name: str) -> None:
        view_layer = bpy.context.view_layer
        for other in view_layer.objects:
            other.select_set(other.name == name)
        view_layer.objects.active = view_layer.objects[name]

    yield from compare("start")
    select("Matte ball")
    operator(bpy.ops.transform.translate, value=(0.9, 0.4, 0.0))
    yield from compare("moved")
    operator(bpy.ops.ed.undo)
    yield from compare("move undone")
    operator(bpy.ops.ed.redo)
    yield from compare("move redone")
    operator(bpy.ops.ed.undo)
    yield from compare("move undone again")
    select("Matte ball")
    operator(bpy.ops.object.delete)
    yield from compare("deleted")
    operator(bpy.ops.ed.undo)
    yield from compare("delete undone")
    select("Matte ball")
    operator(bpy.ops.object.modifier_add, type="ARRAY")
    bpy.data.objects["Matte ball"].modifiers[-1].count = 3  # two more balls beside it
    with session.override(area):
        bpy.ops.ed.undo_push(message="array of 3")
    yield from compare("arrayed")
    operator(bpy.ops.ed.undo)
    operator(bpy.ops.ed.undo)
    yield from compare("array undone")
    operator(bpy.ops.ed.redo)
    operator(bpy.ops.ed.redo)
    yield from compare("array redone")
    select("Matte ball")
    operator(bpy.ops.object.mode_set, mode="EDIT")
    operator(bpy.ops.mesh.select_all, action="SELECT")
    operator(bpy.ops.transform.translate, value=(0.0, 0.0, 0.6))
    yield from compare("edited in edit mode")
    operator(bpy.ops.ed.undo)  # the mesh's own undo: its vertices back, still in Edit Mode
    yield from compare("edit undone in edit mode")
    operator(bpy.ops.ed.redo)
    operator(bpy.ops.object.mode_set, mode="OBJECT")
    yield from compare("edit redone, object mode")


def _traced(viewport):
    """The scene the (one) Rendered viewport traces, None before its first sync."""
    sessions = [s for s in list(viewport._sessions) if not s.closed]
    return sessions[0]._scene if sessions else None


def _render(exported):
    import bvhlab

    image, _ = bvhlab.render(exported, bvhlab.build(exported), *SIZE, backend="cpu", threads=1)
    return image[..., :3]


def _compared(name: str, traced, first) -> dict:
    """The step's figures: the share of pixels where the traced scene and a fresh export differ,
    and where the traced scene and the first picture differ."""
    import bpy
    import numpy as np

    from bvhlab.blender import export_scene

    fresh = export_scene(bpy.context, light_distance=bpy.context.scene.bvhlab.light_distance)
    ours = _render(traced)
    share = float((np.abs(ours - _render(fresh)).max(-1) > PIXEL).mean())
    changed = float((np.abs(ours - first).max(-1) > PIXEL).mean())
    return {"step": name, "differs_from_fresh": share, "differs_from_first": changed}


def _until(condition, timeout: float, what: str):
    from session import until  # at run time, under Blender (the driver imports this file without bpy)

    return until(condition, timeout, what)


# -- checks, run by the driver (no bpy) --------------------------------------------------------
def check(shots: dict, info: dict) -> list[str]:
    failures = []
    done = info.get("steps", [])
    if [s["step"] for s in done] != [name for name, _ in EXPECTED]:
        return [f"steps run: {[s['step'] for s in done]}"]
    for step, (_, changes) in zip(done, EXPECTED):
        if step["differs_from_fresh"] > SHARE:
            failures.append(
                f"{step['step']}: the viewport traces another scene than Blender's "
                f"({100 * step['differs_from_fresh']:.2f}% of the pixels differ)"
            )
        if changes and step["differs_from_first"] <= SHARE:
            failures.append(f"{step['step']}: the picture did not change (the step changed nothing?)")
        if not changes and step["differs_from_first"] > SHARE:
            failures.append(
                f"{step['step']}: the picture is not the first one ({100 * step['differs_from_first']:.2f}% differ)"
            )
    return failures


if __name__ == "__main__":
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).resolve().parent))
    import session as ui_session

    ui_session.run(steps)
