"""Table 1 as CSV, Markdown (with the report's own numbers beside ours) and JSON."""

from __future__ import annotations

import csv
import math
from pathlib import Path

from .. import _json as strict_json
from .._atomic import replacing, write_text
from .protocol import paired_ratio

#: The report's Table 1 (Sponza, 800×600, its GPU): frame ms (average), build ms, tree height.
REPORT_TABLE1 = {
    "median": (41.8, 105, 20),
    "mean": (30.1, 124, 34),
    "sah12": (26.5, 255, 30),
    "sah32": (26.1, 604, 30),
}
#: The two readings of the report's "mean" (§2.3.1): the centroid mean it describes, and the
#: midpoint of the centroid bounds (PBRT's "Middle", which §2.3.1 names as the same method).
MEAN_READINGS = ("mean", "midpoint")
NAMES = {"mean": "mean (centroid mean, as §2.3.1 describes)", "midpoint": "midpoint (PBRT Middle)"}

COLUMNS = [
    "method",
    "frame_ms",
    "frame_ms_lo",
    "frame_ms_hi",
    "frame_cpu_ms",
    "frame_cpu_ms_lo",
    "frame_cpu_ms_hi",
    "build_ms",
    "build_cpu_ms",
    "build_cpu_ms_lo",
    "build_cpu_ms_hi",
    "height",
    "sah_cost",
    "nodes",
    "leaves",
    "primary_mrays_s",
    "device",
]
#: A two-level tree's (an instanced scene, issue 34) columns after those: its TLAS and what the
#: instances make of the meshes' trees (InstancedBvh.stats); written only when a row has them.
TWO_LEVEL_COLUMNS = [
    "instances",
    "meshes",
    "tlas_height",
    "tlas_sah_cost",
    "tlas_nodes",
    "primitives",
    "primitives_flattened",
    "memory_bytes",
]


def samples(row: dict, name: str) -> list[float]:
    """The samples verdicts use ("frame" or "build"): CPU time for builds and for frames rendered on
    the CPU (`frame_clock` "cpu"), where it measures the work and not the neighbours; else wall time."""
    return row[f"{name}_cpu_ms_all" if _cpu(row, name) else f"{name}_ms_all"]


def median_ms(row: dict, name: str) -> float:
    """The median of `samples(row, name)`."""
    return row[f"{name}_cpu_ms" if _cpu(row, name) else f"{name}_ms"]


def _cpu(row: dict, name: str) -> bool:
    return name == "build" or row.get("frame_clock") == "cpu"


def report_row(method: str) -> str:
    """The key of the report's Table 1 row a method is compared with (both mean readings: "mean")."""
    return "mean" if method in MEAN_READINGS else method


def write_csv(rows: list[dict], path: Path) -> Path:
    """One row per method, the report's Table 1 columns first."""
    path.parent.mkdir(parents=True, exist_ok=True)
    with replacing(path, text=True) as f:
        w = csv.writer(f)
        columns = COLUMNS + [c for c in TWO_LEVEL_COLUMNS if any(c in r for r in rows)]
        w.writerow(columns)
        for r in rows:
            w.writerow([_cell(r.get(c)) for c in columns])
    return path


def write_tables(rows: list[dict], out: Path, meta: dict, checks: list[dict], extra_markdown: str = "") -> dict:
    out.mkdir(parents=True, exist_ok=True)
    paths = {"csv": out / "table.csv", "md": out / "table.md", "json": out / "table.json"}
    write_csv(rows, paths["csv"])
    write_text(paths["md"], markdown(rows, meta, checks) + extra_markdown)
    write_text(
        paths["json"],
        strict_json.dumps({"meta": meta, "rows": rows, "checks": checks, "report_table1": REPORT_TABLE1}, indent=1),
    )
    return paths


def markdown(rows: list[dict], meta: dict, checks: list[dict]) -> str:
    clock = "CPU" if rows and rows[0].get("frame_clock") == "cpu" else "wall"
    head = (
        f"| Split method | Frame ms ({clock}) | Frame ms (wall) | Build ms (CPU) | Tree height | SAH cost |"
        " Frame ÷ SAH 12 | Report: frame ms | Report: build ms | Report: height | Report: frame ÷ SAH 12 |"
    )
    lines = [_preamble(meta, clock), "", head, "|" + "|".join(["---"] * (head.count("|") - 1)) + "|"]
    base = next((r for r in rows if r["method"] == "sah12"), None)
    for r in rows:
        rep = REPORT_TABLE1.get(report_row(r["method"]))
        ours = paired_ratio(samples(r, "frame"), samples(base, "frame")).text(2) if base else ""
        rep_cells = (
            [str(rep[0]), str(rep[1]), str(rep[2]), f"{rep[0] / REPORT_TABLE1['sah12'][0]:.2f}"] if rep else [""] * 4
        )
        frame_key = "frame_cpu_ms" if clock == "CPU" else "frame_ms"
        lines.append(
            f"| {NAMES.get(r['method'], r['method'])} | {_spread(r, frame_key)} | {_spread(r, 'frame_ms')} | "
            f"{_spread(r, 'build_cpu_ms')} | {r['height']} | {r['sah_cost']:.1f} | {ours} | "
            + " | ".join(rep_cells)
            + " |"
        )
    lines += [
        "",
        "Medians with [lo–hi], the interval that holds the true median with ≥ 90% confidence (order "
        "statistics over rounds); ratios are medians of per-round ratios. The report's numbers are for "
        "Sponza on its GPU (average frame time): compare the ranking and the ratios, not the milliseconds.",
    ]
    lines += ["", finding(rows), "", ranking(rows), "", "Checks (report §4.2, §5.2):", ""]
    lines += [f"- **{c['verdict']}**: {c['claim']} ({c['section']}) — {c['detail']}" for c in checks]
    return "\n".join(lines) + "\n"


def _preamble(meta: dict, clock: str) -> str:
    why = (
        " Verdicts and ratios use CPU time (all threads of the process), which measures a frame's work on"
        " a shared machine; wall time also measures whoever else is using the cores."
        if clock == "CPU"
        else ""
    )
    return (
        f"Scene **{meta['scene']}** ({meta['triangles']} triangles, {meta['spheres']} spheres), "
        f"{meta['width']}×{meta['height']}, device: {meta['device']}{_threads(meta)}"
        f"{_walk(meta)}. Frame: median of "
        f"{meta['frames']} frames; build: median of {meta['builds']} builds on "
        f"{meta.get('build_threads', 1)} thread(s); "
        f"each after a warm-up that is not counted, methods interleaved round by round. Build settings: "
        f"{meta.get('build_settings', 'one primitive per leaf, largest-extent axis')}.{why}"
    )


def _walk(meta: dict) -> str:
    walk = meta.get("traversal")
    if walk is None:
        return ""
    order = "nearer child first" if walk == "stack" else "the report's fixed depth-first order"
    return f", the {walk} walk ({order})"


def _threads(meta: dict) -> str:
    n = meta.get("render_threads")
    return "" if n is None else " on every core" if n == 0 else f" on {n} thread{'s' if n > 1 else ''}"


def finding(rows: list[dict]) -> str:
    """Which reading of "mean" gives the report's Mean height (34), stated from the heights measured."""
    report_height = REPORT_TABLE1["mean"][2]
    readings = {m: next((r["height"] for r in rows if r["method"] == m), None) for m in MEAN_READINGS}
    if None in readings.values():
        return ""
    matching = [m for m, h in readings.items() if h == report_height]
    said = f"centroid mean {readings['mean']}, midpoint {readings['midpoint']}"
    if matching == ["midpoint"]:
        return (
            f"**Finding:** the report's Mean row has height {report_height}; here the {said}: the report's "
            f"mean is consistent with a split at the midpoint of the centroid bounds (PBRT's Middle, which "
            f"§2.3.1 names beside it) rather than at the centroid mean §2.3.1 describes (one height, on a "
            f"mesh that may differ from the report's by a few triangles)."
        )
    return f"**Finding:** the report's Mean row has height {report_height}; here the {said}: " + (
        f"{' and '.join(matching)} match{'es' if len(matching) == 1 else ''}." if matching else "neither matches."
    )


def ranking(rows: list[dict]) -> str:
    """Methods by median frame time; '<' where the next is slower beyond the spread, '≈' otherwise."""
    ordered = sorted(rows, key=lambda r: median_ms(r, "frame"))
    text = ordered[0]["method"]
    for a, b in zip(ordered, ordered[1:]):
        r = paired_ratio(samples(a, "frame"), samples(b, "frame"))
        text += (" < " if r.known and r.hi < 1 else " ≈ ") + b["method"]
    report = " < ".join(f"{m} ({v[0]})" for m, v in sorted(REPORT_TABLE1.items(), key=lambda kv: kv[1][0]))
    return f"Frame-time ranking: {text} (report: {report})."


def _spread(r: dict, key: str) -> str:
    lo, hi = r.get(f"{key}_lo"), r.get(f"{key}_hi")
    digits = 1 if r[key] >= 10 else 2 if r[key] >= 1 else 3
    if lo is None or math.isnan(lo):
        return f"{r[key]:.{digits}f}"
    return f"{r[key]:.{digits}f} [{lo:.{digits}f}–{hi:.{digits}f}]"


def _cell(v):
    if isinstance(v, float):  # empty where table.json has null (inf was written "inf": an audit)
        return "" if not math.isfinite(v) else f"{v:.4g}"
    return "" if v is None else v
