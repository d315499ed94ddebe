"""Export and build of N collection instances of a 15,744-triangle Suzanne (issue 34): the
instanced export (one mesh, N transforms) against the flat export of before (`instancing=False`,
every instance's triangles in the world), with the bytes each scene stores and the tree build
(InstancedBvh against the flat Bvh). bpy as a module:

    .venv/bin/python bench/export_instances.py [--counts 100,1000] [--flat-max 1000] [--repeat 3]
        [--json bench/results/export_instances.json]

Best of --repeat runs (the machine is shared); the flat export runs only up to --flat-max
instances (1,000 flat instances take seconds and gigabytes)."""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests" / "blender"))
sys.path.insert(0, str(ROOT / "tests" / "python"))

import bpy  # noqa: E402


def scene_of(count: int) -> None:
    from blender_instance_scenes import base_scene, suzanne

    scene = base_scene()
    source = bpy.data.collections.new("Source")
    source.objects.link(suzanne(subdivisions=2))
    for i in range(count):
        empty = bpy.data.objects.new(f"Instance {i}", None)
        empty.instance_type, empty.instance_collection = "COLLECTION", source
        scene.collection.objects.link(empty)
        empty.location = (3.0 * (i % 40), 3.0 * (i // 40), 0.0)
        empty.rotation_euler = (0.0, 0.0, 0.1 * i)
    bpy.context.view_layer.update()


def stored_bytes(scene) -> int:
    arrays = [scene.triangles, scene.spheres, scene.tri_material, *scene.meshes, *scene.mesh_tri_material]
    if scene.instance_transforms is not None:
        arrays += [scene.instance_transforms, scene.instance_mesh]
    return sum(a.nbytes for a in arrays)


def best(work, repeat: int) -> tuple[float, object]:
    times, result = [], None
    for _ in range(repeat):
        start = time.perf_counter()
        result = work()
        times.append(time.perf_counter() - start)
    return min(times) * 1e3, result


def measure(count: int, flat: bool, repeat: int) -> dict:
    import bvhlab
    from bvhlab.blender import export_scene

    scene_of(count)
    row: dict = {"instances": count}
    for label, instancing in (("instanced", True), ("flat", False)):
        if label == "flat" and not flat:
            continue
        ms, exported = best(lambda instancing=instancing: export_scene(bpy.context, instancing=instancing), repeat)
        build_ms, bvh = best(lambda exported=exported: bvhlab.build(exported), repeat)
        row[label] = {
            "export_ms": round(ms, 1),
            "build_ms": round(build_ms, 1),
            "stored_mb": round(stored_bytes(exported) / 1e6, 2),
            "world_triangles": len(exported.flattened().triangles) if instancing else len(exported.triangles),
            "tree_mb": round(
                (bvh.stats["meshes_memory_bytes"] + bvh.stats["tlas_memory_bytes"]) / 1e6
                if isinstance(bvh, bvhlab.InstancedBvh)
                else bvh.stats["memory_bytes"] / 1e6,
                2,
            ),
        }
        del exported, bvh
    return row


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--counts", default="100,1000")
    parser.add_argument("--flat-max", type=int, default=1000)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--json", type=Path)
    args = parser.parse_args()
    rows = [measure(int(n), int(n) <= args.flat_max, args.repeat) for n in args.counts.split(",")]
    for row in rows:
        print(json.dumps(row))
    if args.json:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps({"export_instances": rows}, indent=2) + "\n")


if __name__ == "__main__":
    main()
