"""The Python code of the README and docs/api.md runs as written: each file's blocks in order in one
namespace (a later block uses an earlier block's names), as a reader would paste them. Blocks for
Blender (`import bpy`) are the add-on checks' business (tests/blender)."""

import re
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]


def python_blocks(path: Path) -> list[str]:
    blocks = re.findall(r"^```python\n(.*?)^```", path.read_text(), re.S | re.M)
    return [b for b in blocks if "import bpy" not in b]


@pytest.mark.parametrize("name", ["README.md", "docs/api.md"])
def test_the_documented_code_runs(name, tmp_path, monkeypatch):
    blocks = python_blocks(ROOT / name)
    assert blocks, f"{name} has no Python block"
    monkeypatch.chdir(tmp_path)  # what the blocks write lands here
    namespace: dict = {}
    for block in blocks:
        exec(compile(block, f"{name} block", "exec"), namespace)
    # the blocks did what they say: a tree over the scene, hits, and (README) an image
    bvh = namespace["bvh"]
    assert bvh.stats["primitives"] == len(namespace["tris"])
    assert np.isfinite(namespace["hits"]["t"]).any()
    if "image" in namespace:
        assert namespace["image"].shape == (600, 800, 4)
