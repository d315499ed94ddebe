"""Final renders (F12, bpy.ops.render.render, `blender -b file -f N` / `-a`) into Blender's Render
Result: Combined, Depth and heatmap passes, progress and Esc the way Blender shows them.

`sync` runs in RenderEngine.update (Blender holds the scene for it); `render` in RenderEngine.render.
An engine instance lives for one render, or for as long as Blender keeps it: with Render ▸
Performance ▸ Persistent Data on, the same instance (and depsgraph) serves every frame of an
animation and every later F12, so only what the depsgraph reports as changed is read again.
"""

from __future__ import annotations

import time
import warnings

from . import passes, records
from .scene_tree import BuildSettings, SceneTree
from .settings import backend, trace_settings
from .tracer import TraceCancelled, open_tracer

#: Progress (RenderEngine.update_progress) at the start of each stage.
BUILD_START, TRACE_START, PASSES_START = 0.05, 0.35, 0.85


class FinalRender:
    """One engine instance's final-render state: the scene it keeps between frames."""

    def __init__(self):
        from bvhlab.blender import LiveScene

        self.live = LiveScene("visible", require_camera=True)
        self.error: str | None = None
        self.report = None
        self.notes: list[str] = []

    def sync(self, depsgraph) -> None:
        """Export what changed since the last frame (all of it the first time)."""
        from bvhlab.blender import ExportError, ExportWarning

        self.error, self.notes = None, []
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", ExportWarning)
            try:
                self.report = self.live.sync(depsgraph)
            except ExportError as error:
                self.error = str(error)
        self.notes = [str(w.message) for w in caught if issubclass(w.category, ExportWarning)]

    def render(self, engine, depsgraph) -> None:
        blender_scene = depsgraph.scene
        if self.error is not None:
            engine.report({"ERROR"}, f"bvhlab: {self.error}")
            return
        for note in self.notes:
            engine.report({"WARNING"}, f"bvhlab: {note}")
        try:
            self._render(engine, depsgraph, blender_scene)
        except Exception as error:  # reported, never raised into Blender's render thread
            import bvhlab

            if isinstance(error, (bvhlab.BuildCancelled, TraceCancelled)):
                engine.update_stats("", "Cancelled")
                return
            if not isinstance(error, (ValueError, RuntimeError, OSError)):
                import traceback

                traceback.print_exc()
            engine.report({"ERROR"}, f"bvhlab: {error}")

    def _render(self, engine, depsgraph, blender_scene) -> None:
        key = records.key(blender_scene)
        scene = self.live.scene
        tracer = open_tracer(backend(blender_scene))
        tree, update = self._tree(engine, blender_scene, key)
        if engine.test_break():
            return
        width, height = engine.resolution_x, engine.resolution_y
        settings = trace_settings(blender_scene, viewport=False)
        engine.update_progress(TRACE_START)
        engine.update_stats("", f"Tracing {width} × {height}, {settings.samples} samples per pixel on {tracer.device}")
        result = engine.begin_result(0, 0, width, height, layer=depsgraph.view_layer.name)
        try:
            layer = result.layers[0]
            images, timings = tracer.trace(
                scene,
                tree.bvh,
                scene.camera,
                width,
                height,
                settings,
                cancelled=engine.test_break,
                depth=layer.passes.get(passes.DEPTH) is not None,
                heat=layer.passes.get(passes.HEATMAP) is not None,
            )
            passes.write(layer, passes.COMBINED, images.color)
            engine.update_progress(PASSES_START)
            extra = self._extra_passes(layer, images)
            engine.update_result(result)
        finally:
            engine.end_result(result)
        engine.update_progress(1.0)
        record = {
            "device": tracer.device,
            "backend": tracer.backend,
            "note": tracer.note,
            "tree": update.action,
            "build_ms": update.ms,
            "trace_ms": timings["trace_ms"],
            "total_ms": timings["total_ms"],
            **extra,
            "sync": self.report,
            "totals": self.live.totals,
            "size": (width, height),
            "samples": settings.samples,
        }
        with records.lock:
            records.last_final[key] = record
        engine.update_stats("", _summary(record))

    def _tree(self, engine, blender_scene, key):
        """The scene's tree for final renders (kept across engine instances), made to fit."""
        with records.lock:
            tree = records.final_trees.setdefault(key, SceneTree())
        settings = BuildSettings.of(blender_scene)
        engine.update_progress(BUILD_START)
        engine.update_stats("", f"Building BVH ({settings.method})")

        def progress(fraction: float) -> bool:
            engine.update_progress(BUILD_START + (TRACE_START - BUILD_START) * fraction)
            return not engine.test_break()

        started = time.perf_counter()
        update = tree.update(self.live.scene, settings, self.report is not None and self.report.refittable, progress)
        if update.action != "kept":
            engine.update_stats("", f"BVH {update.action} in {(time.perf_counter() - started) * 1e3:.0f} ms")
        return tree, update

    @staticmethod
    def _extra_passes(layer, images) -> dict:
        """Depth and heatmap, when the view layer asks for them (the same render made them)."""
        if images.depth is not None:
            passes.write(layer, passes.DEPTH, images.depth)
        if images.heat is not None:
            passes.write(layer, passes.HEATMAP, images.heat)
        return {}


def _summary(record: dict) -> str:
    parts = [
        f"BVH {record['tree']}" + (f" {record['build_ms']:.0f} ms" if record["tree"] != "kept" else ""),
        f"trace {record['trace_ms']:.0f} ms",
    ]
    if "heatmap_ms" in record:
        parts.append(f"heatmap {record['heatmap_ms']:.0f} ms")
    return " | ".join(parts) + f" | {record['device']}"
