"""bench/_peers.py's reading of a --peers list: bvh_bench specs whose own options are
comma-separated, in a list that is comma-separated too."""

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "bench"))
import _peers  # noqa: E402


def test_split_specs_keeps_a_specs_options_together():
    text = "tinybvh:,bvhlab:,bvhlab:leaf=8,bvhlab:bins=14,leaf=8,embree:medium,bvhlab:method=sah,bins=12,axis=largest"
    assert _peers.split_specs(text) == [
        "tinybvh:",
        "bvhlab:",
        "bvhlab:leaf=8",
        "bvhlab:bins=14,leaf=8",
        "embree:medium",
        "bvhlab:method=sah,bins=12,axis=largest",
    ]


def test_split_specs_single_and_prefixless_first():
    assert _peers.split_specs("bvhlab:bins=14,leaf=8") == ["bvhlab:bins=14,leaf=8"]
    # a first piece without a system stays a spec of its own (bvh_bench names the bad system)
    assert _peers.split_specs("leaf=8,tinybvh:") == ["leaf=8", "tinybvh:"]
