"""Shared helpers of the benchmarks: timing, Embree as the peer, tables, JSON."""

from __future__ import annotations

import json
import os
import platform
import statistics
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

RESULTS = Path(__file__).resolve().parent / "results"


def median_time(fn, repeat: int) -> tuple[float, object]:
    """Median wall time of `repeat` calls, in seconds, and the last result."""
    times, result = [], None
    for _ in range(repeat):
        t = time.perf_counter()
        result = fn()
        times.append(time.perf_counter() - t)
    return statistics.median(times), result


def pin_to_cores(n: int) -> None:
    """Restrict this process (and Embree's TBB pool, created later) to the first n cores."""
    cores = sorted(os.sched_getaffinity(0))[:n]
    os.sched_setaffinity(0, cores)


class Embree:
    """Embree 4 through embreex: build time is the lazy commit at the first query, measured alone
    (the Python-speed copy into the TriangleMesh, about 0.8 s for 1M triangles, is excluded)."""

    def __init__(self, tris: np.ndarray):
        from embreex import rtcore_scene as rtcs
        from embreex.mesh_construction import TriangleMesh

        self._rtcs, self._mesh = rtcs, TriangleMesh
        self.tris = tris
        self.scene = None

    def build(self) -> float:
        scene = self._rtcs.EmbreeScene()
        self._mesh(scene, self.tris)
        o = np.zeros((1, 3), np.float32)
        d = np.ones((1, 3), np.float32)
        t = time.perf_counter()
        scene.run(o, d)  # commits the BVH
        elapsed = time.perf_counter() - t
        self.scene = scene
        return elapsed

    def trace(self, origins, dirs) -> np.ndarray:
        return self.scene.run(origins, dirs)  # primID per ray, rtcIntersect1 per ray


def machine() -> dict:
    """What ran the benchmark. The model name alone does not tell hosts apart ("AMD EPYC" is every
    generation on this project's VMs, whose speed differed 2× between a Zen 1 host and a later one),
    so the CPU's family, model and stepping, its cache sizes and the load average go in too."""
    info = _cpuinfo(_read("/proc/cpuinfo"))
    caches = {}
    for index in sorted(Path("/sys/devices/system/cpu/cpu0/cache").glob("index*")):
        level, kind, size = (_read(index / f) for f in ("level", "type", "size"))
        if level and size:
            caches[f"L{level}{'d' if kind == 'Data' else 'i' if kind == 'Instruction' else ''}"] = size
    load = _read("/proc/loadavg").split()[:3]
    return {
        "cpu": info.get("model name", "unknown"),
        "cpu_id": "/".join(info.get(k, "?") for k in ("vendor_id", "cpu family", "model", "stepping")),
        "mhz": info.get("cpu MHz"),
        "caches": caches,
        "cores": os.cpu_count(),
        "load": [float(x) for x in load],
        "python": platform.python_version(),
        "date": time.strftime("%Y-%m-%d %H:%M:%S"),
    }


def machine_line(m: dict) -> str:
    """machine()'s record in one line, for the head of a benchmark's log."""
    caches = " ".join(f"{k} {v}" for k, v in m.get("caches", {}).items())
    load = "/".join(f"{x:.1f}" for x in m.get("load", []))
    return f"machine: {m['cpu']} ({m.get('cpu_id', '?')}), {m['cores']} cores, {caches}; load {load}; {m['date']}"


def _read(path) -> str:
    try:
        return Path(path).read_text().strip()
    except OSError:
        return ""


def _cpuinfo(text: str) -> dict:
    """The first processor's fields of /proc/cpuinfo, by name."""
    out = {}
    for line in text.splitlines():
        if not line.strip():
            if out:
                break
            continue
        key, _, value = line.partition(":")
        out.setdefault(key.strip(), value.strip())
    return out


def print_table(headers: list[str], rows: list[list], title: str = "") -> str:
    cells = [[_fmt(c) for c in r] for r in rows]
    widths = [max(len(h), *(len(r[i]) for r in cells)) if cells else len(h) for i, h in enumerate(headers)]
    lines = []
    if title:
        lines.append(title)
    lines.append("  ".join(h.rjust(w) if i else h.ljust(w) for i, (h, w) in enumerate(zip(headers, widths))))
    lines.append("  ".join("-" * w for w in widths))
    for r in cells:
        lines.append("  ".join(c.rjust(w) if i else c.ljust(w) for i, (c, w) in enumerate(zip(r, widths))))
    text = "\n".join(lines)
    print(text, flush=True)
    return text


def _fmt(c) -> str:
    if isinstance(c, float):
        return f"{c:.3g}" if abs(c) < 10 else f"{c:.1f}" if abs(c) < 1000 else f"{c:.0f}"
    return str(c)


def json_path(name: str) -> Path:
    """Where --json NAME writes: a bare file name goes into bench/results, a path (with a folder)
    where it says. Checked when the arguments are read, so a run of minutes cannot end in a
    folder that does not exist."""
    path = RESULTS / name if Path(name).name == name else Path(name)
    if not path.parent.is_dir() and path.parent != RESULTS:
        raise SystemExit(f"--json {name}: the folder {path.parent} does not exist")
    return path


def write_json(name: str, data: dict) -> Path:
    RESULTS.mkdir(parents=True, exist_ok=True)
    from bvhlab._atomic import write_text  # whole or not at all: a stopped run leaves the old file

    return write_text(json_path(name), json.dumps(data, indent=1) + "\n")


def run_child(script: str, args: list[str], cores: int | None = None) -> dict:
    """Run a benchmark part in a fresh process (so core pinning and Embree's pool start clean),
    pinned to the first `cores` cores when given."""
    pin = ["taskset", "-c", ",".join(str(c) for c in sorted(os.sched_getaffinity(0))[:cores])] if cores else []
    out = subprocess.run([*pin, sys.executable, script, *args], capture_output=True, text=True)
    sys.stderr.write(out.stderr)
    out.check_returncode()
    return json.loads(out.stdout.strip().splitlines()[-1])
