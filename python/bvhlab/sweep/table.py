"""Where a sweep keeps its results: one JSON file per finished cell in DIR/cells/ (each written whole
or not at all, so an interrupted sweep keeps every cell it finished), and the table of the spec's
cells rebuilt from them: DIR/results.parquet (pyarrow) and DIR/results.csv, one row per cell."""

from __future__ import annotations

import csv
import io
import json
from pathlib import Path

from .._atomic import write_bytes, write_text

CELLS = "cells"
PARQUET, CSV = "results.parquet", "results.csv"


def cell_path(out: Path, key: str) -> Path:
    return out / CELLS / f"{key}.json"


def store_row(out: Path, row: dict) -> None:
    path = cell_path(out, row["key"])
    path.parent.mkdir(parents=True, exist_ok=True)
    write_text(path, json.dumps(row, sort_keys=True))


def stored_rows(out: Path, keys: list[str]) -> dict[str, dict]:
    """The stored row of each key that has one (a file that cannot be read counts as not run)."""
    rows = {}
    for key in keys:
        try:
            rows[key] = json.loads(cell_path(out, key).read_text())
        except (OSError, ValueError):
            continue
    return rows


def write_table(out: Path, rows: list[dict], columns: list[str]) -> tuple[Path, Path]:
    """The rows as Parquet and CSV, with `columns` in this order (a row's missing value is null)."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    table = pa.Table.from_pylist([{c: row.get(c) for c in columns} for row in rows])
    buffer = io.BytesIO()
    pq.write_table(table, buffer)
    parquet = write_bytes(out / PARQUET, buffer.getvalue())
    text = io.StringIO()
    writer = csv.DictWriter(text, fieldnames=columns, extrasaction="ignore", lineterminator="\n")
    writer.writeheader()
    writer.writerows(rows)
    return parquet, write_text(out / CSV, text.getvalue())
