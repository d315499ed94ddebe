"""Stats files (bvhlab.stats_files) of values the API may hold: a numpy array among the stats (a
TypeError, "Object of type ndarray is not JSON serializable", helper probe 2026-12-07), numpy
scalars and values that are not finite (JSON null; the CSV as Python writes them)."""

import csv
import json

import numpy as np

from bvhlab.stats_files import write_stats


def test_numpy_arrays_scalars_and_nan_are_written_to_json_and_csv(tmp_path):
    stats = {
        "nodes": np.int64(7),
        "sah_cost": np.float32(2.5),
        "build_ms": float("nan"),
        "nodes_per_depth": np.array([1, 2, 4]),
        "extra": np.array([[1.0, np.inf], [0.5, 2.0]]),
    }
    json_file, csv_file = tmp_path / "s.json", tmp_path / "s.csv"
    write_stats(stats, {"scene": "test"}, json_file=json_file, csv_file=csv_file)
    got = json.loads(json_file.read_text())["stats"]
    assert got == {
        "nodes": 7,
        "sah_cost": 2.5,
        "build_ms": None,
        "nodes_per_depth": [1, 2, 4],
        "extra": [[1.0, None], [0.5, 2.0]],
    }
    rows = list(csv.reader(csv_file.open()))
    assert ["nodes_per_depth", "2", "4"] in rows and ["nodes", "", "7"] in rows
