"""`bvhlab sweep`: build statistics and CPU ray throughput over many scenes and a grid of build
settings, one Dask task per cell (python -m bvhlab sweep SPEC.toml --out DIR). spec: the SPEC.toml;
cells: the cells and their keys; task: one cell's work; runner: running them (in-process or on
Dask); table: results on disk; plot: SAH cost against build time; summary: ratios to a baseline
method (summary.md and its plot)."""

from .cells import Cell, plan_cells
from .runner import SweepResult, local_cluster, run_sweep
from .spec import SweepSpec, read_spec

__all__ = ["Cell", "SweepResult", "SweepSpec", "local_cluster", "plan_cells", "read_spec", "run_sweep"]
