"""Stats files (bvhlab.stats_files) of values the API may hold: a numpy array among the stats (a
TypeError, "Object of type ndarray is not JSON serializable", helper probe 2026-12-07), numpy
scalars and values that are not finite (JSON null; in the CSV an empty field, where it wrote `nan`
and `inf`)."""

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


def test_csv_leaves_empty_what_json_writes_null(tmp_path):
    """The CSV wrote `nan` and `inf` where the JSON has null (a None was already empty): each
    missing value is an empty field now, which CSV readers (pandas: NaN) take as missing."""
    stats = {
        "build_ms": float("nan"),
        "sah_cost": np.float64(np.inf),
        "bins": None,
        "height": 3,
        "mesh_sah_cost": [1.5, float("nan"), -np.inf],
    }
    json_file, csv_file = tmp_path / "s.json", tmp_path / "s.csv"
    write_stats(stats, {}, json_file=json_file, csv_file=csv_file)
    written = json.loads(json_file.read_text())["stats"]
    rows = {(r["metric"], r["index"]): r["value"] for r in csv.DictReader(csv_file.open())}
    assert rows == {
        ("build_ms", ""): "",
        ("sah_cost", ""): "",
        ("bins", ""): "",
        ("height", ""): "3",
        ("mesh_sah_cost", "0"): "1.5",
        ("mesh_sah_cost", "1"): "",
        ("mesh_sah_cost", "2"): "",
    }
    for (metric, index), value in rows.items():  # empty exactly where the JSON has null
        json_value = written[metric] if index == "" else written[metric][int(index)]
        assert (value == "") == (json_value is None), metric
