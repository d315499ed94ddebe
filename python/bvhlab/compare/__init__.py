"""Reproduce the report's Table 1 (frame time, build time, tree height per split method) and its
Figures 3–5, with more columns: SAH cost, nodes, leaves, primary-ray throughput, device."""
from .checks import report_checks
from .measure import measure_methods
from .report import REPORT_TABLE1, write_csv, write_tables

__all__ = ["measure_methods", "report_checks", "write_csv", "write_tables", "REPORT_TABLE1"]
