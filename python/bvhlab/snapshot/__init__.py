"""Raster previews of a scene and its BVH with moderngl (OpenGL via EGL, headless).

moderngl and Blender's `gpu` module fight over the current OpenGL context in one process, so the
drawing runs in a child process (`python -m bvhlab.snapshot.worker`): the scene goes to it as an
`.npz`, the picture comes back as a PNG.
"""

from __future__ import annotations

import json
import subprocess
import sys
import tempfile
from pathlib import Path

from .._progress import Ticker
from ..render_options import DEFAULT_HEIGHT, DEFAULT_WIDTH
from .raster import RASTER_PROJECTIONS


def run_snapshot(
    scene_spec: str,
    build_kwargs: dict,
    out: Path,
    depth_range: tuple[int, int],
    width: int = DEFAULT_WIDTH,
    height: int = DEFAULT_HEIGHT,
) -> Path:
    """One picture with the boxes of depths depth_range[0] … depth_range[1]."""
    return _run(
        scene_spec,
        build_kwargs,
        out,
        ["--depth", str(depth_range[0]), str(depth_range[1]), "--size", str(width), str(height)],
    )


#: A sheet's panel by default (width, height).
SHEET_PANEL = (320, 240)


def run_sheet(
    scene_spec: str,
    build_kwargs: dict,
    out: Path,
    panel_width: int = SHEET_PANEL[0],
    panel_height: int = SHEET_PANEL[1],
) -> Path:
    """A grid with one panel per depth, 0 … height - 1."""
    return _run(scene_spec, build_kwargs, out, ["--sheet", "--size", str(panel_width), str(panel_height)])


def _run(scene_spec: str, build_kwargs: dict, out: Path, extra: list[str]) -> Path:
    from ..library import load_scene

    scene, name = load_scene(scene_spec)
    if not scene.has_geometry:
        raise ValueError(f"scene '{name}' has no geometry")
    from .._render_settings import default_camera

    # a scene reaching near ±2^40 is left without one: default_camera raises the render's reason
    # ("snapshot failed: AttributeError" in the child before)
    projection = (scene.camera or default_camera(scene)).projection
    if projection not in RASTER_PROJECTIONS:  # before the child process: its error would come back late
        raise ValueError(
            f"scene '{name}': its camera is {projection}; the snapshot draws {' and '.join(RASTER_PROJECTIONS)} "
            "cameras (bvhlab render traces every camera)"
        )
    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as tmp:
        npz = Path(tmp) / "scene.npz"
        scene.save(npz)
        cmd = [
            sys.executable,
            "-m",
            "bvhlab.snapshot.worker",
            str(npz),
            "--name",
            name,
            "--build",
            json.dumps(build_kwargs),
            "--out",
            str(out),
            *extra,
        ]
        # a ticker on the terminal while the worker builds and draws (a sheet of a 1M-triangle
        # scene: 7.6 s with nothing shown, a helper's audit)
        with Ticker("drawing the snapshot"):
            done = subprocess.run(cmd, capture_output=True, text=True)
    if done.returncode != 0:
        lines = (done.stderr or done.stdout).strip().splitlines()
        raise RuntimeError(f"snapshot failed: {lines[-1] if lines else f'exit code {done.returncode}'}")
    for line in done.stderr.splitlines():  # the worker's warnings (a depth range below the tree)
        if line.startswith("warning: "):
            print(line, file=sys.stderr)
    return out
