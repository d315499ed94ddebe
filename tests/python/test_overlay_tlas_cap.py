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


def test_a_render_whose_overlay_leaves_boxes_out_says_so():
    """render(..., overlay_level="blas") over 40 instances of a 20,000-triangle knot drew the boxes
    of 8 instances and said nothing (the note reached the add-on's sidebar alone: an audit)."""
    from bvhlab.library import procedural

    n = 40
    transforms = np.tile(np.eye(3, 4, dtype=np.float32), (n, 1, 1))
    transforms[:, 0, 3] = np.arange(n) * 4.0
    knot = procedural.torus_knot(20000).astype(np.float32)
    scene = bvhlab.Scene(triangles=knot, instance_mesh=np.zeros(n, np.int32), instance_transforms=transforms)
    tree = bvhlab.build(scene)
    options = dict(backend="cpu", overlay_depth=(0, 40))
    _, timings = bvhlab.render(scene, tree, 40, 8, overlay_level="blas", **options)
    assert timings["overlay_note"] == "BLAS boxes of 8 of 40 instances (at most 200,000 boxes)"
    assert timings["overlay_note"] == levels.cap_note(tree, "blas", 0, 40)
    _, timings = bvhlab.render(scene, tree, 40, 8, overlay_level="tlas", **options)  # every TLAS box drawn
    assert "overlay_note" not in timings
