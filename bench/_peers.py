"""bvh_bench (bench/cpp) from Python: building it, the scenes and rays it reads, pinned and
repeated runs, callgrind instruction counts, and embreex timed beside it."""

from __future__ import annotations

import json
import math
import os
import re
import shutil
import statistics
import subprocess
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
BUILD = ROOT / "build" / "bench"


def build_bvh_bench(tinybvh: str | None, target: str = "bvh_bench") -> Path:
    """Configures and builds bench/cpp's bvh_bench (or `target`, e.g. tlas_bench) in build/bench
    (Release, Embree 3 when libembree-dev is installed, tinybvh when a local copy is given)."""
    args = [
        "cmake",
        "-S",
        str(ROOT),
        "-B",
        str(BUILD),
        "-G",
        "Ninja",
        "-DCMAKE_BUILD_TYPE=Release",
        "-DBVHLAB_TESTS=ON",
        "-DBVHLAB_VULKAN=OFF",
        f"-DBVHLAB_TINYBVH_DIR={tinybvh or ''}",
    ]
    subprocess.run(args, check=True, stdout=subprocess.DEVNULL)
    subprocess.run(["cmake", "--build", str(BUILD), "--target", target], check=True, stdout=subprocess.DEVNULL)
    return BUILD / "bench" / "cpp" / target


def scenes(names: list[str]) -> dict[str, np.ndarray]:
    """Triangle arrays (T,3,3) by name, each with a size (250k, 1m): sponza (bundled); room1m (a
    model in a room, the non-uniform case); uniform1m (small random triangles); and scenes unlike
    them: repeat1m (a knot repeated 20 times in a row), rods1m (2,000 long thin rods at random
    angles), vast1m (a knot in an empty room 10,000 units wide)."""
    from bvhlab.library import bundled_dir, procedural, sponza

    out = {}
    for name in names:
        if name == "sponza":  # bundled (blender_scenes/sponza.npz), the source's bits
            out[name] = sponza.load_triangles(bundled_dir() / sponza.FILE_NAME)
        elif name.startswith("room"):
            out[name] = procedural.model_in_room(_count(name))
        elif name.startswith("uniform"):
            n = _count(name)
            out[name] = procedural.random_triangles(n, size=1.0 / n ** (1 / 3), seed=1)
        elif name.startswith("repeat"):
            out[name] = procedural.repeated_row(_count(name))
        elif name.startswith("rods"):
            out[name] = procedural.rods(_count(name))
        elif name.startswith("vast"):
            out[name] = procedural.model_in_vast_room(_count(name))
        else:
            raise SystemExit(f"bench: unknown scene {name}")
    return out


def write_inputs(folder: Path, scene: str, tris: np.ndarray) -> tuple[Path, dict[str, Path]]:
    """bvh_bench's inputs for a scene, written into `folder`: its triangles (.f32) and each of its
    ray sets (rays_for) as a file, by set name."""
    mesh = folder / f"{scene}.f32"
    tris.tofile(mesh)
    rays = {}
    for name, r in rays_for(scene, tris).items():
        rays[name] = folder / f"{scene}_{name}.f32"
        r.tofile(rays[name])
    return mesh, rays


def _count(name: str) -> int:
    m = re.search(r"(\d+)([km])$", name)
    if not m:
        raise SystemExit(f"bench: scene {name} needs a size such as 250k or 1m")
    return int(m.group(1)) * (1000 if m.group(2) == "k" else 1_000_000)


def rays_for(name: str, tris: np.ndarray) -> dict[str, np.ndarray]:
    """Random rays (origins in the bounds, uniform directions) and primary rays (640×480) as N×6,
    and shadow rays from the random rays' hits (N×7, shadow_rays)."""
    from bvhlab.library import procedural

    o, d = procedural.random_rays(tris, 200_000, seed=3)
    out = {"random": np.concatenate([o, d], 1)}
    if name == "sponza":  # the report's Figure 6 view (bvhlab.library.sponza.CAMERA)
        out["primary"] = _pinhole((-110, 20, -4), (100, 45, 2), 60.0)
    else:
        o, d = procedural.camera_rays(tris, 640, 480)
        out["primary"] = np.concatenate([o, d], 1)
    # From the random rays' hits, which lie inside the scene: the generated scenes' cameras look at
    # them from outside (room1m's primary rays hit the room's outer walls, so every shadow ray to a
    # light inside it would be blocked by the wall it starts on). Sponza's y is up, the others' z.
    out["shadow"] = shadow_rays(tris, out["random"].astype(np.float32), 1 if name == "sponza" else 2)
    return {k: np.ascontiguousarray(v, np.float32) for k, v in out.items()}


def shadow_rays(tris: np.ndarray, rays: np.ndarray, up: int) -> np.ndarray:
    """Shadow rays as a renderer casts them (N×7: origin, direction, tmax): from where each of
    `rays` (N×6) hits the scene, backed off along it by 1e-4 of its distance plus 1e-5 of the
    point's largest coordinate (~80 float32 steps: a hit 1 unit from a ray's origin on vast1m's
    wall at 5,000 was backed off by less than a float step there, so the shadow ray started on the
    wall, at a true t of 0, which float rounding put on either side: 5 rays of 200,000 occluded
    for bvhlab, not for Embree or tinybvh), to a point light in the
    upper middle of the scene's bounds (60% of the way up axis `up`, at the centre of the other
    two), the direction unit length and tmax the light's
    distance, so a ray is occluded exactly where the point lies in shadow. The hits come from
    bvhlab's closest-hit query (every peer's hit agrees with it to 1e-4 on these sets)."""
    import bvhlab

    o, d = np.ascontiguousarray(rays[:, :3]), np.ascontiguousarray(rays[:, 3:])
    t = bvhlab.build(tris).intersect(o, d)["t"]
    hit = np.isfinite(t)
    at = o[hit].astype(np.float64) + d[hit] * t[hit, None].astype(np.float64)
    back = t[hit] * 1e-4 + 1e-5 * np.abs(at).max(1)
    points = at - d[hit] * (back / np.linalg.norm(d[hit], axis=1))[:, None]
    lo, hi = tris.reshape(-1, 3).min(0), tris.reshape(-1, 3).max(0)
    light = (lo + hi) / 2
    light[up] = lo[up] + 0.6 * (hi[up] - lo[up])
    to_light = light - points
    dist = np.linalg.norm(to_light, axis=1)
    return np.ascontiguousarray(np.concatenate([points, to_light / dist[:, None], dist[:, None]], 1), np.float32)


def _pinhole(position, look_at, fov_y: float, width: int = 640, height: int = 480) -> np.ndarray:
    pos, look = np.array(position, np.float64), np.array(look_at, np.float64)
    fwd = (look - pos) / np.linalg.norm(look - pos)
    right = np.cross(fwd, (0.0, 1.0, 0.0))
    right /= np.linalg.norm(right)
    up = np.cross(right, fwd)
    tan = math.tan(math.radians(fov_y) / 2)
    ys, xs = np.mgrid[0:height, 0:width]
    px = ((xs + 0.5) / width * 2 - 1) * tan * width / height
    py = (1 - (ys + 0.5) / height * 2) * tan
    d = fwd + px[..., None] * right + py[..., None] * up
    d /= np.linalg.norm(d, axis=-1, keepdims=True)
    return np.concatenate([np.broadcast_to(pos, d.shape).reshape(-1, 3), d.reshape(-1, 3)], 1)


def ray_args(name: str, path: Path) -> list[str]:
    """bvh_bench's arguments for a ray set: shadow rays (N×7) after --shadow (bench/ab_batch.py
    passed them as rays of 6 floats: its shadow rows were other rays' closest hits)."""
    return ["--shadow", str(path)] if name == "shadow" else [str(path)]


def cores(threads: int) -> str:
    """The first `threads` cores this process may use, for taskset."""
    return ",".join(str(c) for c in sorted(os.sched_getaffinity(0))[:threads])


def run(exe: Path, args: list[str], threads: int) -> dict:
    """One bvh_bench run pinned to `threads` cores; its JSON."""
    cmd = ["taskset", "-c", cores(threads), str(exe), *args, "--threads", str(threads)]
    out = subprocess.run(cmd, capture_output=True, text=True)
    if out.returncode:
        raise SystemExit(f"bench: {' '.join(cmd)} failed:\n{out.stderr}")
    return json.loads(out.stdout)


def instructions(exe: Path, args: list[str]) -> int | None:
    """Instructions of one build (or one pass over rays) on one thread, counted by callgrind
    between bvh_bench's start and stop marks; None without valgrind."""
    if not shutil.which("valgrind"):
        return None
    cmd = [
        "valgrind",
        "--tool=callgrind",
        "--instr-atstart=no",
        "--callgrind-out-file=/dev/null",
        str(exe),
        "once",
        *args,
        "--threads",
        "1",
    ]
    out = subprocess.run(cmd, capture_output=True, text=True)
    m = re.search(r"I\s+refs:\s+([\d,]+)", out.stderr)
    return int(m.group(1).replace(",", "")) if m else None


def embreex_commit_seconds(tris: np.ndarray, repeat: int) -> list[float] | None:
    """Embree 4 through embreex: the lazy BVH commit at the first query, timed alone (the copy
    into the TriangleMesh, about 0.8 s for 1M triangles, is excluded); None without embreex."""
    try:
        from embreex import rtcore_scene as rtcs
        from embreex.mesh_construction import TriangleMesh
    except ImportError:
        return None
    times = []
    o, d = np.zeros((1, 3), np.float32), np.ones((1, 3), np.float32)
    for _ in range(repeat):
        scene = rtcs.EmbreeScene()
        TriangleMesh(scene, tris)
        t = time.perf_counter()
        scene.run(o, d)
        times.append(time.perf_counter() - t)
    return times


def median(xs: list[float]) -> float:
    return statistics.median(xs)


def split_specs(text: str) -> list[str]:
    """A --peers list of bvh_bench specs: comma-separated, where a piece without a `system:`
    prefix continues the spec before it (bvhlab:bins=14,leaf=8 is one spec, as bvh_bench reads
    a spec's options comma-separated)."""
    specs: list[str] = []
    for piece in text.split(","):
        if ":" in piece or not specs:
            specs.append(piece)
        else:
            specs[-1] += "," + piece
    return specs


def chosen_rows(text: str, rows: list[tuple[str, str]], tinybvh: str | None) -> list[tuple[str, str]]:
    """The (label, spec) rows a --peers list asks for, in its order: a spec of no row in `rows`
    (bvhlab:bins=14,leaf=8) is its own row, named by its spec (it used to be dropped without a
    word); tinybvh specs need its directory."""
    asked = split_specs(text)
    if not tinybvh and any(spec.startswith("tinybvh") for spec in asked):
        raise SystemExit("--peers tinybvh:...: give --tinybvh DIR (or BVHLAB_TINYBVH_DIR)")
    known = {spec: label for label, spec in rows}
    return [(known.get(spec, f"{spec.split(':')[0]} ({spec})"), spec) for spec in asked]
