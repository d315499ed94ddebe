"""Box colourings by a measure (bvhlab.inspect.measures): values on the ramp follow the measure's
order, span [0, 1] as the legend says, and line up with the rows of Bvh.boxes."""

import numpy as np
import pytest

import bvhlab
from bvhlab.inspect.measures import LOG_DECADES, MEASURES, box_order, measure_values
from bvhlab.library import procedural


@pytest.fixture(scope="module")
def data_and_tree():
    tree = bvhlab.build(bvhlab.Scene(triangles=procedural.torus_knot(4000)), max_leaf_size=4)
    return tree.node_data(), tree


@pytest.mark.parametrize("leaves_only", [False, True])
def test_box_order_is_the_order_of_bvh_boxes(data_and_tree, leaves_only):
    data, tree = data_and_tree
    lo, hi, depth = tree.boxes(leaves_only=leaves_only)
    order = box_order(data, leaves_only)
    np.testing.assert_array_equal(data.lo[order], lo)
    np.testing.assert_array_equal(data.hi[order], hi)
    np.testing.assert_array_equal(data.depth[order], depth)


@pytest.mark.parametrize("measure", list(MEASURES))
def test_values_follow_the_measure_and_the_legend(data_and_tree, measure):
    data, _ = data_and_tree
    values, legend = measure_values(data, measure)
    raw = {
        "sah_share": data.sah_share,
        "leaf_size": data.prim_count.astype(float),
        "child_overlap": data.child_overlap,
        "epo": data.epo / data.epo_cost,
    }[measure]
    assert values.dtype == np.float32 and values.min() >= 0 and values.max() <= 1
    order = np.argsort(raw, kind="stable")
    assert np.all(np.diff(values[order]) >= -1e-7), "a larger measure never gets a bluer colour"
    if legend.log:
        top = raw.argmax()
        assert values[top] == pytest.approx(1.0) and legend.high == pytest.approx(raw.max())
        inside = raw >= legend.low
        expected = np.log(raw[inside] / legend.low) / np.log(legend.high / legend.low)
        np.testing.assert_allclose(values[inside], expected, rtol=1e-5, atol=1e-6)
        if measure != "leaf_size":
            assert legend.low == pytest.approx(legend.high * 10**-LOG_DECADES)
    else:
        np.testing.assert_allclose(values, np.clip(raw, 0, 1), rtol=1e-6)
    assert "blue" in legend.text() and "red" in legend.text()


def test_an_unknown_measure_is_refused(data_and_tree):
    with pytest.raises(ValueError, match="measure must be one of"):
        measure_values(data_and_tree[0], "depth")
