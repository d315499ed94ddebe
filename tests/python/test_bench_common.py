"""bench/_common.py's record of the machine a benchmark ran on."""

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "bench"))
import _common  # noqa: E402

CPUINFO = """processor\t: 0
vendor_id\t: AuthenticAMD
cpu family\t: 23
model\t\t: 1
model name\t: AMD EPYC
stepping\t: 2
cpu MHz\t\t: 1996.249

processor\t: 1
vendor_id\t: AuthenticAMD
cpu family\t: 25
model\t\t: 17
model name\t: AMD EPYC 9004
"""


def test_cpuinfo_reads_the_first_processor_only():
    info = _common._cpuinfo(CPUINFO)
    assert info["cpu family"] == "23" and info["model"] == "1" and info["stepping"] == "2"
    assert info["model name"] == "AMD EPYC" and info["cpu MHz"] == "1996.249"
    assert _common._cpuinfo("") == {}


def test_machine_names_the_host_beyond_its_model_name():
    m = _common.machine()
    assert m["cores"] >= 1 and len(m["load"]) == 3
    assert m["cpu_id"].count("/") == 3
    if "cpu family" in _common._cpuinfo(_common._read("/proc/cpuinfo")):  # x86
        assert "?" not in m["cpu_id"].split("/")[1]
    line = _common.machine_line(m)
    assert line.startswith("machine: ") and m["cpu_id"] in line and m["date"] in line
