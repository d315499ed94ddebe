"""Render inputs a helper's audit found accepted or refused in words that named the wrong thing."""

import numpy as np
import pytest

import bvhlab
from bvhlab.library import showcase


@pytest.mark.parametrize("color", [(2, -1, 0), (3e38, 0, 0)])
def test_a_line_colour_out_of_range_is_refused(color):
    """(2, -1, 0) drew pixels of -1; (3e38, 0, 0) with 2×2 samples 276 infinite pixels."""
    with pytest.raises(ValueError, match=r"line_color must be three numbers in \[0, 1e\+30\]"):
        bvhlab.RenderOptions(line_color=color).core()


def test_a_view_outside_the_coordinate_range_is_refused_as_a_camera_is():
    """A View at 2e12 was taken; without a light its render blamed the default light's position."""
    with pytest.raises(ValueError, match=r"camera position \(0.0, 0.0, 2000000000000.0\) lies outside"):
        bvhlab.View((0, 0, 2e12), (0, 0, -1))
    with pytest.raises(ValueError, match="camera position"):
        bvhlab.Camera((0, 0, 2e12), (0, 0, 0))


def test_material_indices_of_other_triangles_are_named_with_their_counts():
    scene = showcase.whitted()
    scene.tri_material = np.zeros(len(scene.triangles), np.int32)
    scene.triangles = scene.triangles[:10]  # the indices are the old triangles'
    with pytest.raises(
        ValueError, match=rf"one material index per triangle is needed: got {len(scene.tri_material)} for 10"
    ):
        bvhlab.render(scene, bvhlab.build(scene), 8, 8, backend="cpu")


def test_a_zero_scale_transform_says_so():
    """Its message read "|determinant| 0 is -nan of the product of its axes' lengths"."""
    transforms = np.zeros((1, 3, 4), np.float32)
    scene = bvhlab.Scene(
        meshes=[showcase.whitted().triangles], instance_mesh=np.array([1]), instance_transforms=transforms
    )
    with pytest.raises(ValueError, match=r"cannot be inverted \(an axis of length 0: a zero scale\)"):
        bvhlab.build(scene)


def test_renderer_arguments_are_checked_not_read_by_truthiness():
    with pytest.raises(TypeError, match="validation must be True or False"):
        bvhlab.Renderer("cpu", validation="no")  # was True
    with pytest.raises(TypeError, match="device must be a Vulkan device's index or a part of its name"):
        bvhlab.Renderer("auto", device=1.5)
    with pytest.raises(ValueError, match="names a Vulkan device, and the backend is 'cpu'"):
        bvhlab.Renderer("cpu", device="nvidia")  # was ignored
    scene = showcase.whitted()
    job = bvhlab.Renderer("cpu").start(scene, bvhlab.build(scene), 4, 4)
    job.run()
    with pytest.raises(TypeError, match="color must be True or False"):
        job.result(color="no")  # gave a colour image
    assert job.result(color=False).color is None


@pytest.mark.vulkan
def test_a_device_index_may_be_an_int():
    """The docstring's "index or name substring": device=1 was a TypeError in nanobind's words."""
    renderer = bvhlab.Renderer("vulkan", device=0, validation=True)  # lavapipe here (make test installs it)
    assert renderer.device == bvhlab.Renderer("vulkan", device="0").device
    assert renderer.validation_errors == 0


@pytest.mark.parametrize("n", [17, 0, -1])
def test_samples_per_axis_is_named_with_its_range(n):
    """-1 was told "must be between 0 and 2147483648" (an audit): the range is 1 to 16."""
    scene = showcase.whitted()
    with pytest.raises(ValueError, match=rf"samples_per_axis must be between 1 and 16, got {n}"):
        bvhlab.render(scene, bvhlab.build(scene), 4, 4, backend="cpu", samples_per_axis=n)
