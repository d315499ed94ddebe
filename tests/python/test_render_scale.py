"""A scene scaled as a whole renders the same image (Whitted shading has no falloff with distance),
on the CPU reference and on Vulkan, up to the coordinate range: a floor of triangles whose edges
multiply past ~1.8e19 was shaded with a zero normal (unlit, and as a mirror reflecting nothing),
and a thin lens's rays towards a focus distance past ~1e19 had no direction. A lens reaching
outside the coordinate range is refused."""

import numpy as np
import pytest

import bvhlab
from bvhlab.library.showcase import quad


def scene(k: float, mirror: bool, aperture: float = 0.0) -> bvhlab.Scene:
    floor = (quad((-8, -8, 0), (8, -8, 0), (8, 8, 0), (-8, 8, 0)).astype(np.float64) * k).astype(np.float32)
    material = bvhlab.Material((0.8, 0.6, 0.4), reflective=0.9 if mirror else 0.0)
    return bvhlab.Scene(
        triangles=floor,
        materials=[material, bvhlab.Material((0.2, 0.3, 0.9))],
        spheres=np.array([[0, 0, 2 * k, k]], np.float32),
        sphere_material=np.ones(1, np.int32),
        camera=bvhlab.Camera((0, -10 * k, 4 * k), (0, 0, 0), aperture_radius=aperture * k, focus_distance=10.77 * k),
        light=bvhlab.Light((3 * k, -4 * k, 8 * k)),
        sky=(0.3, 0.3, 0.3),
    )


@pytest.fixture(scope="module")
def renderers():
    vulkan = bvhlab.Renderer("vulkan", validation=True)
    yield {"cpu": bvhlab.Renderer("cpu"), "vulkan": vulkan}
    assert vulkan.validation_errors == 0, vulkan.validation_messages()


@pytest.mark.parametrize("backend", ["cpu", "vulkan"])
@pytest.mark.parametrize("mirror", [False, True], ids=["matte", "mirror"])
@pytest.mark.parametrize("k", [1e9, 1e10, 3e10])
def test_a_scaled_scene_renders_as_at_scale_one(renderers, backend, mirror, k):
    r = renderers[backend]
    base, _ = r.render(s := scene(1.0, mirror), bvhlab.build(s), 32, 24)
    scaled, _ = r.render(s := scene(k, mirror), bvhlab.build(s), 32, 24)
    bad = np.abs(scaled - base).max(-1) > 0.02
    assert bad.mean() < 0.02, (bad.sum(), scaled[20, 4], base[20, 4])


@pytest.mark.parametrize("backend", ["cpu", "vulkan"])
def test_a_thin_lens_focused_far_away_has_rays(renderers, backend):
    """Focus distance 1e30: the lens's rays still point at the scene (they had no direction)."""
    s = scene(1.0, False, aperture=0.01)
    sharp, _ = renderers[backend].render(s, bvhlab.build(s), 32, 24, samples_per_axis=2)
    s.camera = bvhlab.Camera((0, -10, 4), (0, 0, 0), aperture_radius=0.01, focus_distance=1e30)
    far, _ = renderers[backend].render(s, bvhlab.build(s), 32, 24, samples_per_axis=2)
    assert np.abs(far - sharp).max(-1).mean() < 0.05


@pytest.mark.parametrize("aperture", [1e20, 2.0**40])
def test_a_lens_outside_the_coordinate_range_is_refused(aperture):
    with pytest.raises(ValueError, match="aperture_radius must keep the lens within the coordinate range"):
        bvhlab.Camera((0, -10, 4), (0, 0, 0), aperture_radius=aperture, focus_distance=10.0)
