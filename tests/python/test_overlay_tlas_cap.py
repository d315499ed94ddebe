"""The overlay's boxes of a two-level tree (bvhlab.inspect.levels.shown_boxes, which the viewport
draws and Pick Box picks among) are at most `cap` also where the TLAS alone has more nodes in the
depth range: 1,000,000 instances gave 2,000,000 TLAS boxes (61 MB of texture, 1.3-1.7 s to make at
every change of the depth range, Pick Box 3.5 s a click) under a note saying "at most 200,000"."""

import numpy as np
import pytest

import bvhlab
from bvhlab.inspect import levels


def _scattered(n: int):
    tri = np.array([[[0, 0, 0], [0.1, 0, 0], [0, 0.1, 0]]], np.float32)
    transforms = np.tile(np.eye(3, 4, dtype=np.float32), (n, 1, 1))
    transforms[:, 0, 3] = np.arange(n, dtype=np.float32)
    scene = bvhlab.Scene(
        triangles=np.zeros((0, 3, 3), np.float32),
        meshes=[tri],
        mesh_tri_material=[np.zeros(1, np.int32)],
        instance_mesh=np.ones(n, np.int32),
        instance_transforms=transforms,
    )
    return bvhlab.build(scene)


@pytest.mark.parametrize("level", ["tlas", "both"])
def test_tlas_boxes_are_capped_shallowest_first_and_said(level):
    bvh = _scattered(400)
    full = levels.shown_boxes(bvh, "tlas", 0, 63)
    assert len(full.lo) > 700 and full.note == ""
    capped = levels.shown_boxes(bvh, level, 0, 63, cap=100)
    assert len(capped.lo) <= 100, f"{len(capped.lo)} boxes drawn with a cap of 100"
    assert np.all(np.diff(capped.depth.astype(int)) >= 0)
    assert np.array_equal(capped.lo, full.lo[: len(capped.lo)])  # the shallowest ones
    assert "TLAS" in capped.note
    assert levels.cap_note(bvh, level, 0, 63, cap=100) == capped.note
