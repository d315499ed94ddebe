"""BVH statistics as JSON and CSV files: the one writer of `bvhlab build --json/--csv` and the
add-on's Export stats (no bpy). Method comparisons are written by bvhlab.compare. Both files are
written whole or not at all (bvhlab._atomic)."""

from __future__ import annotations

import csv
from pathlib import Path

from . import _json as strict_json
from ._atomic import replacing, write_text
from ._checks import output_file
from .two_level_stats import MESH_METRICS

#: Per-depth and per-size lists in `Bvh.stats`, per-mesh lists in `InstancedBvh.stats`; every
#: other entry is one value.
LIST_METRICS = ("nodes_per_depth", "leaves_per_depth", "leaf_size_histogram", *MESH_METRICS)


def json_path(path) -> Path:
    """`path` checked as a stats JSON file before any work: OutputPathError when it is a folder,
    lies under a file, or does not end in .json (it is never renamed)."""
    return output_file(path, (".json",), "stats file")


def csv_path(path) -> Path:
    """As json_path, for the CSV."""
    return output_file(path, (".csv",), "stats file")


def write_stats_json(path: Path, stats: dict, about: dict) -> None:
    """{"about": {...scene, file, scope...}, "stats": <Bvh.stats, unchanged>}."""
    path.parent.mkdir(parents=True, exist_ok=True)
    write_text(path, strict_json.dumps({"about": about, "stats": stats}, indent=1) + "\n")


def write_stats_csv(path: Path, stats: dict) -> None:
    """Long format, one value per row: `metric,index,value`. Single values leave `index` empty;
    nodes_per_depth and leaves_per_depth have the depth as index, leaf_size_histogram the leaf size,
    the mesh_* lists of a two-level tree the mesh."""
    path.parent.mkdir(parents=True, exist_ok=True)
    with replacing(path, text=True) as f:
        out = csv.writer(f)
        out.writerow(["metric", "index", "value"])
        for name, value in stats.items():
            if name in LIST_METRICS:
                out.writerows([name, i, v] for i, v in enumerate(value))
            else:
                out.writerow([name, "", value])
