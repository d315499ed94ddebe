"""Table 1 as CSV, Markdown (with the report's own numbers beside ours) and JSON."""
from __future__ import annotations

import csv
import json
from pathlib import Path

#: The report's Table 1 (Sponza, 800×600, its GPU): frame ms, build ms, tree height.
REPORT_TABLE1 = {
    "median": (41.8, 105, 20),
    "mean": (30.1, 124, 34),
    "sah12": (26.5, 255, 30),
    "sah32": (26.1, 604, 30),
}

COLUMNS = ["method", "frame_ms", "build_ms", "height", "sah_cost", "nodes", "leaves", "primary_mrays_s", "device"]


def write_csv(rows: list[dict], path: Path) -> Path:
    """One row per method, the report's Table 1 columns first."""
    path.parent.mkdir(parents=True, exist_ok=True)
    with path.open("w", newline="") as f:
        w = csv.writer(f)
        w.writerow(COLUMNS)
        for r in rows:
            w.writerow([_cell(r[c]) for c in COLUMNS])
    return path


def write_tables(rows: list[dict], out: Path, meta: dict, checks: list[dict]) -> dict[str, Path]:
    out.mkdir(parents=True, exist_ok=True)
    paths = {"csv": out / "table.csv", "md": out / "table.md", "json": out / "table.json"}
    write_csv(rows, paths["csv"])
    paths["md"].write_text(markdown(rows, meta, checks))
    paths["json"].write_text(json.dumps({"meta": meta, "rows": rows, "checks": checks,
                                         "report_table1": REPORT_TABLE1}, indent=1))
    return paths


def markdown(rows: list[dict], meta: dict, checks: list[dict]) -> str:
    head = ("| Split method | Frame (ms) | Build (ms) | Tree height | SAH cost | Nodes | Primary Mrays/s |"
            " Report: frame (ms) | Report: build (ms) | Report: height |")
    lines = [f"Scene **{meta['scene']}** ({meta['triangles']} triangles, {meta['spheres']} spheres), "
             f"{meta['width']}×{meta['height']}, {meta['frames']} frames after a warm-up, "
             f"build = median of {meta['builds']}; device: {meta['device']}.", "",
             head, "|" + "|".join(["---"] * (head.count("|") - 1)) + "|"]
    for r in rows:
        rep = REPORT_TABLE1.get(r["method"])
        rep_cells = [f"{rep[0]}", f"{rep[1]}", f"{rep[2]}"] if rep else ["", "", ""]
        lines.append(f"| {r['method']} | {r['frame_ms']:.1f} | {r['build_ms']:.1f} | {r['height']} | "
                     f"{r['sah_cost']:.2f} | {r['nodes']} | {r['primary_mrays_s']:.2f} | " + " | ".join(rep_cells) + " |")
    lines += ["", "The report's numbers are for Sponza on its GPU; compare the ranking, not the milliseconds.", ""]
    lines += ["Checks (report §4.2, §5.2):", ""]
    lines += [f"- {'holds' if c['holds'] else 'does NOT hold'}: {c['claim']} — {c['detail']}" for c in checks]
    return "\n".join(lines) + "\n"


def _cell(v):
    return f"{v:.4g}" if isinstance(v, float) else v
