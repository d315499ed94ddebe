"""The engine's settings, read from the scene's one PropertyGroup (scene.bvhlab) that the sidebar
panel also uses: the tree (BVHLAB_PG_settings.build_config) and the trace
(BVHLAB_PG_settings.render_options) come from there; this module adds the engine's own choices."""

from __future__ import annotations

import os

#: The viewport leaves one core to Blender's UI thread (orbiting stays fluid while a frame traces
#: or the tree builds). Final renders use Blender's render threads (final_threads).
VIEWPORT_THREADS = max(1, (os.cpu_count() or 2) - 1)


def final_threads(blender_scene) -> int:
    """The threads of a final render (its tree and its trace on the CPU): Render Properties ▸
    Performance ▸ Threads, as Cycles takes them. `render.threads` is the count Blender itself
    works out: every core with Auto-detect, the number with Fixed, N after `blender -t N`."""
    return max(1, int(blender_scene.render.threads))


def fixed_light_distance(blender_scene) -> float | None:
    """The light calibration the scene fixes (BVHLAB_PG_settings.light_distance), or None where it
    is left to be measured (0); the one reading of it, the CLI's too (bvhlab.blender.light)."""
    from bvhlab.blender.light import saved_light_distance

    return saved_light_distance(blender_scene)


def backend(blender_scene) -> str:
    return blender_scene.bvhlab.backend
