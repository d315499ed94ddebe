"""The scene a Renderer takes for the one on the device (Renderer._uploaded): an upload that fails
leaves the device holding the empty scene (sky) the core puts in place of the freed one, so no
scene may be named as uploaded then. Reachable where the render-scene cache keeps the scene last
uploaded beside the one whose upload failed: a two-level scene rendered, then its overlay copy of
BLAS boxes (kept beside it) failing to upload (out of device memory), then the scene again: it
rendered the sky. The failure is made by a stand-in for the device's upload that puts the empty
scene there, as the core does, and raises."""

import numpy as np
import pytest
from test_render_instanced import _two_cloud_scene

import bvhlab
from bvhlab.render_options import options_from


def test_a_failed_upload_names_no_scene_as_uploaded():
    try:
        renderer = bvhlab.Renderer("vulkan", validation=True)
    except bvhlab.VulkanUnavailable as error:
        pytest.skip(f"no Vulkan: {error}")
    real = renderer._vulkan
    scene = _two_cloud_scene()
    tree = bvhlab.build(scene)
    empty = bvhlab.Scene(camera=scene.camera)
    nothing = renderer._cache.get(empty, bvhlab.build(np.zeros((0, 3, 3), np.float32)), options_from(None, {}))

    class FailingUpload:
        fail = False

        def __getattr__(self, name):
            return getattr(real, name)

        def upload(self, render_scene):
            if not self.fail:
                return real.upload(render_scene)
            self.fail = False
            real.upload(nothing)  # the core's scene in place of the one freed
            raise RuntimeError("out of device memory (a stand-in)")

    renderer._vulkan = device = FailingUpload()

    def depth(**options):
        job = renderer.start(scene, tree, 160, 100, samples_per_axis=1, **options)
        job.run()
        return job.result(cost=False).depth

    before = depth()
    assert (before < 1e10).sum() > 0  # the clouds are seen (their small triangles)
    device.fail = True
    with pytest.raises(RuntimeError, match="out of device memory"):
        depth(overlay_level="blas", overlay_depth=(1, 1))
    np.testing.assert_array_equal(depth(), before)  # uploaded again, not the sky
    assert renderer.validation_errors == 0, renderer.validation_messages()
