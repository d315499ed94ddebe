"""BVH statistics as JSON and CSV files: the one writer of `bvhlab build --json/--csv` and the
add-on's Export stats (no bpy). Method comparisons are written by bvhlab.compare. The files are
written together, whole or not at all (bvhlab._atomic.write_together)."""

from __future__ import annotations

import csv
import io
from pathlib import Path

from . import _json as strict_json
from ._atomic import write_together
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


def write_stats(stats: dict, about: dict, json_file: Path | None = None, csv_file: Path | None = None) -> None:
    """The stats to `json_file` (stats_json) and `csv_file` (stats_csv), those given, together: an
    interrupt or a refused write leaves both as they were (one at a time, a new JSON could stand
    beside an old CSV). Their folders are made."""
    files = {}
    if json_file is not None:
        files[Path(json_file)] = stats_json(stats, about).encode()
    if csv_file is not None:
        files[Path(csv_file)] = stats_csv(stats).encode()
    for path in files:
        path.parent.mkdir(parents=True, exist_ok=True)
    write_together(files)


def stats_json(stats: dict, about: dict) -> str:
    """{"about": {...scene, file, scope...}, "stats": <Bvh.stats, unchanged>}."""
    return strict_json.dumps({"about": about, "stats": stats}, indent=1) + "\n"


def stats_csv(stats: dict) -> str:
    """Long format, one value per row: `metric,index,value`. Single values leave `index` empty;
    nodes_per_depth and leaves_per_depth have the depth as index, leaf_size_histogram the leaf size,
    the mesh_* lists of a two-level tree the mesh. A value the JSON writes as null (None, NaN, ±inf:
    strict_json.plain) is an empty field, as CSV readers take a missing value (pandas: NaN); it was
    written `nan` (None empty)."""
    text = io.StringIO()
    out = csv.writer(text)
    out.writerow(["metric", "index", "value"])
    for name, value in strict_json.plain(stats).items():
        if name in LIST_METRICS:
            out.writerows([name, i, v] for i, v in enumerate(value))
        else:
            out.writerow([name, "", value])
    return text.getvalue()
