"""Reproduce the report's Table 1 (frame time, build time, tree height per split method), its
claims, its §4.1 overlay measurement and Figures 3–6, with a measurement protocol (protocol.py)
and more columns: SAH cost, nodes, leaves, primary-ray throughput, device."""

from .checks import report_checks
from .measure import REPORT_BUILD, build_settings, measure_methods
from .report import REPORT_TABLE1, write_csv, write_tables

__all__ = [
    "measure_methods",
    "build_settings",
    "report_checks",
    "write_csv",
    "write_tables",
    "REPORT_TABLE1",
    "REPORT_BUILD",
]
