"""A LiveScene sync (what the Rendered viewport and F12 with Persistent Data run at every depsgraph
update) in a scene of N objects while one of them is moved, bpy as a module: one LiveScene that
takes the moved instances' matrices from the updates (bvhlab/blender/placed_only.py) and one that
walks the depsgraph at every sync (`place_from_updates=False`, what every sync did before), both
synced from the same updates in one depsgraph handler, in alternating order, by thread CPU time.

Scenes: N linked duplicates of one box (instances of one mesh), and N boxes of their own meshes
of which the changed one has changed before (a mover: its own instance). Changes: the box moved
(as a drag in the viewport), the frame changed with the box's location keyframed (playback), a
vertex of the box's own mesh moved (an edit: `mesh.update()`, as a modifier's setting names it),
or the frame changed with a shape key of the box keyframed (a deforming object's playback), or
the box is an analytic sphere (mesh 0's) and moved.
After each placed sync, the tree update that follows it (the add-on's `SceneTree.update` with the
sync's `refittable`, one thread): a new TLAS after a move, the changed object's tree refit after
an edit.

    .venv/bin/python bench/live_sync.py [--counts 2000,20000] [--moves 9] [--changes move,sphere]
        [--json live_sync.json]
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
import warnings
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests" / "blender"))
sys.path.insert(0, str(Path(__file__).resolve().parent))

import _common  # noqa: E402
import bpy  # noqa: E402
import harness  # noqa: E402

import bvhlab  # noqa: E402
from bvhlab.blender import LiveScene  # noqa: E402
from bvhlab.blender.sphere import SPHERE_PROPERTY  # noqa: E402

sys.path.insert(0, str(ROOT))
from addon.trees import SceneTree  # noqa: E402


def scene_of(count: int, shared: bool):
    """`count` unit boxes on a grid (one mesh for all where `shared`), a camera and a light."""
    scene = harness.empty_scene()
    harness.add_camera((-30.0, -30.0, 30.0), (0.0, 0.0, 0.0))
    harness.add_point_light((0.0, 0.0, 40.0))
    first = harness.add_box("Box0", (0.0, 0.0, 0.0), size=0.5)
    side = round(count ** (1 / 3)) + 1
    for i in range(1, count):
        data = first.data if shared else first.data.copy()
        obj = bpy.data.objects.new(f"Box{i}", data)
        scene.collection.objects.link(obj)
        obj.location = (i % side, (i // side) % side, i // (side * side))
    bpy.context.view_layer.update()
    return scene, first


#: The changes measured: (name, whether it is a frame change).
CHANGES = (("move", False), ("frame", True), ("edit", False), ("shape key", True), ("sphere", False))


def measure(count: int, shared: bool, moves: int, change: str = "move") -> dict:
    """Syncs after `moves` changes of one object (CHANGES; the module's docstring)."""
    scene, moved = scene_of(count, shared)
    frames = dict(CHANGES)[change]
    if change == "frame":
        for frame, x in ((1, 0.0), (moves + 2, 5.0)):
            moved.location.x = x
            moved.keyframe_insert("location", frame=frame)
    elif change == "shape key":
        moved.shape_key_add(name="Basis")
        key = moved.shape_key_add(name="Up")
        for point in key.data:
            point.co.z += 0.5
        for frame, value in ((1, 0.0), (moves + 2, 1.0)):
            key.value = value
            key.keyframe_insert("value", frame=frame)
    elif change == "sphere":
        moved[SPHERE_PROPERTY] = True
    if frames:
        scene.frame_set(1)
    lives = {"placed": LiveScene("visible"), "walked": LiveScene("visible", place_from_updates=False)}
    times: dict[str, list[float]] = {name: [] for name in lives}
    flags: list[bool] = []
    tree, tree_ms, actions = SceneTree(bvhlab.BuildConfig()), [], []
    order = list(lives)

    def synced(scene, depsgraph):
        for name in order:
            start = time.thread_time()
            report = lives[name].sync(depsgraph, scene)
            times[name].append((time.thread_time() - start) * 1e3)
            if name == "placed":
                flags.append(report.placed_only)
                start = time.thread_time()
                update = tree.update(lives[name].scene, refittable=report.refittable, threads=1)
                tree_ms.append((time.thread_time() - start) * 1e3)
                actions.append(update.action)

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for live in lives.values():
            live.sync(bpy.context.evaluated_depsgraph_get(), scene)
        tree.update(lives["placed"].scene, threads=1)
        handlers = bpy.app.handlers.frame_change_post if frames else bpy.app.handlers.depsgraph_update_post
        handlers.append(synced)
        try:
            for k in range(moves + 1):  # the first move makes a box of its own mesh a mover
                order.reverse()
                if frames:
                    scene.frame_set(k + 2)
                elif change == "edit":
                    moved.data.vertices[0].co.z += 0.05 if k % 2 else -0.05
                    moved.data.update()
                else:
                    moved.location.x += 0.25 if k % 2 else -0.25
                bpy.context.view_layer.update()
        finally:
            handlers.remove(synced)
    return {
        "objects": count,
        "change": change,
        "one_mesh": shared,
        "placed_ms": statistics.median(times["placed"][1:]),
        "walked_ms": statistics.median(times["walked"][1:]),
        "placed_only": flags[1:],
        "tree_ms": statistics.median(tree_ms[1:]),
        "tree_actions": actions[1:],
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--counts", default="2000,20000")
    ap.add_argument("--moves", type=int, default=9)
    ap.add_argument("--changes", default=",".join(name for name, _ in CHANGES))
    ap.add_argument("--json", default="live_sync.json")
    args = ap.parse_args()
    _common.json_path(args.json)
    machine = _common.machine()
    print(_common.machine_line(machine), file=sys.stderr, flush=True)
    changes = args.changes.split(",")
    unknown = [c for c in changes if c not in dict(CHANGES)]
    if unknown:  # before any is measured
        raise SystemExit(f"live_sync: unknown change {', '.join(map(repr, unknown))}")
    rows = []
    for count in (int(c) for c in args.counts.split(",")):
        for change in changes:
            # an edit of the shared mesh changes every duplicate: their own meshes only
            for shared in (True, False) if change in ("move", "frame", "sphere") else (False,):
                row = measure(count, shared, args.moves, change)
                rows.append(row)
                print(row, file=sys.stderr, flush=True)
    _common.print_table(
        [
            "objects",
            "change",
            "one mesh",
            "walk ms",
            "placed ms",
            "walk ÷ placed",
            "placed every time",
            "tree ms",
            "tree",
        ],
        [
            [
                r["objects"],
                r["change"],
                "yes" if r["one_mesh"] else "no",
                f"{r['walked_ms']:.1f}",
                f"{r['placed_ms']:.1f}",
                f"{r['walked_ms'] / r['placed_ms']:.1f}",
                all(r["placed_only"]),
                f"{r['tree_ms']:.2f}",
                "/".join(sorted(set(r["tree_actions"]))),
            ]
            for r in rows
        ],
        title=f"LiveScene sync after one object changed or a frame changed, medians of {args.moves} (thread CPU time)",
    )
    _common.write_json(args.json, {"machine": machine, "rows": rows})


if __name__ == "__main__":
    main()
