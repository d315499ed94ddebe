"""Geometry that reaches near ±MAX_COORDINATE is valid (probe): the Scene is made without a camera
where the one framing it would stand outside the range, the tree builds and takes rays, and a
render without a camera says what to give."""

import numpy as np
import pytest

import bvhlab
from bvhlab.scene import MAX_COORDINATE
from bvhlab.scene_parts import default_light


def _wide_triangle() -> np.ndarray:
    r = np.float32(0.9 * MAX_COORDINATE)
    return np.array([[[-r, -r, 0], [r, -r, 0], [0, r, 0]]], np.float32)


def test_a_flat_scene_near_the_range_limit_is_made_and_takes_rays():
    tris = _wide_triangle()
    scene = bvhlab.Scene(triangles=tris)  # the default camera would stand at ~3e12: none is made
    assert scene.camera is None
    bvh = bvhlab.build(scene)
    hits = bvh.intersect(np.array([[0, 0, 1e6]], np.float32), np.array([[0, 0, -1]], np.float32))
    assert hits["prim"][0] == 0 and hits["t"][0] == np.float32(1e6)


def test_an_instance_moved_near_the_range_limit_is_made_and_takes_rays():
    tris = np.array([[[-1, -1, 0], [1, -1, 0], [0, 1, 0]]], np.float32)
    t = np.repeat(np.eye(3, 4, dtype=np.float32)[None], 2, 0)
    t[1, :, :3] *= np.float32(0.9 * MAX_COORDINATE)
    scene = bvhlab.Scene(triangles=tris, instance_mesh=np.zeros(2, np.int32), instance_transforms=t)
    tree = bvhlab.build(scene)
    hits = tree.intersect(np.array([[0, 0, 5]], np.float32), np.array([[0, 0, -1]], np.float32))
    assert hits["t"][0] == 5 and hits["prim"][0] == 0


def test_a_render_without_a_camera_asks_for_one_and_renders_with_one():
    scene = bvhlab.Scene(triangles=_wide_triangle())
    bvh = bvhlab.build(scene)
    with pytest.raises(ValueError, match="default camera.*give one: the scene's camera, or the render's camera="):
        bvhlab.render(scene, bvh, 4, 3, backend="cpu")
    camera = bvhlab.Camera((0.0, -1e11, 1e11), (0.0, 0.0, 0.0))
    image, _ = bvhlab.render(scene, bvh, 4, 3, backend="cpu", camera=camera)
    assert np.isfinite(image).all()


def test_a_scene_within_reach_keeps_its_default_camera():
    tris = _wide_triangle() * np.float32(1e-3)
    assert bvhlab.Scene(triangles=tris).camera is not None


def _light_beside(camera) -> np.ndarray:
    """The default light's place as documented: 0.3 of the camera's distance to its target to the
    right and up of the camera (numpy, independent of the core's)."""
    position, target, up = (np.array(v, np.float64) for v in (camera.position, camera.look_at, camera.up))
    forward = target - position
    right = np.cross(forward, up)
    return position + 0.3 * np.linalg.norm(forward) * (right / np.linalg.norm(right) + up / np.linalg.norm(up))


def test_a_default_light_near_the_range_limit_is_moved_within_it():
    """The probe's scene: triangles at x = 1e6 and x = 1e12, both within the range: the camera that
    frames them stands within it, the default light beside the camera did not, and the Scene (and
    the Blender export of such a scene) was refused for a light it had not been given. The light is
    now moved towards the camera until it is within the range; the scene renders."""
    tris = np.array([[[1e6, 0, 0], [1e6 + 1, 0, 0], [1e6, 1, 0]], [[1e12, 0, 0], [1e12 + 1e9, 0, 0], [1e12, 1e9, 0]]])
    near = bvhlab.Scene(triangles=(tris * 1e-3).astype(np.float32))  # within reach: where documented
    np.testing.assert_allclose(near.light.position, _light_beside(near.camera), rtol=1e-9)
    scene = bvhlab.Scene(triangles=tris.astype(np.float32))
    assert scene.camera is not None and np.abs(scene.camera.position).max() <= MAX_COORDINATE
    light, beside, camera = np.array(scene.light.position), _light_beside(scene.camera), np.array(scene.camera.position)
    assert np.abs(beside).max() > MAX_COORDINATE >= np.abs(light).max() > 0.98 * MAX_COORDINATE
    way = (light - camera) / (beside - camera)  # on the way from the camera to where it was
    np.testing.assert_allclose(way, way[0], rtol=1e-9)
    assert 0 < way[0] < 1
    # geometry reaching past the margin (x = 1.09e12 of 1.0995e12): the light still off its plane
    edge = np.array([[[1.09e12, 0, 0], [1.09e12, 1e9, 0], [1.09e12, 0, 1e9]]], np.float32)
    lit = bvhlab.Scene(triangles=edge)
    assert lit.camera is not None and np.abs(lit.light.position).max() <= MAX_COORDINATE
    assert lit.light.position[0] != lit.camera.look_at[0], "not in the triangle's plane x = 1.09e12"
    image, _ = bvhlab.render(scene, bvhlab.build(scene), 8, 6, backend="cpu")
    assert np.isfinite(image).all()


def test_the_default_light_depends_on_the_view_not_on_the_lengths_of_its_vectors():
    """A render without a light puts one beside the camera. From a View it was placed by the point
    position + forward, so the same view with forward ×100 (or ×0.01) lit the scene from elsewhere
    (1,856 of 3,072 pixels off by up to 0.81), and up ×10 set it 10× as high; far from the origin
    (a unit forward at 1e8) that point was the position itself in float32 and a valid View was
    refused ("camera position and look_at coincide"). A View's light is now placed for the point
    one unit along its direction, and up counts as a direction (Camera's too), on both backends."""
    rng = np.random.default_rng(3)
    tris = (rng.random((300, 3, 3)) * 4 - 2).astype(np.float32)
    scene = bvhlab.Scene(triangles=tris)
    scene.light = None  # no light: the renders place the default one
    bvh = bvhlab.build(scene)
    forward = np.array([0.2, 1.0, -0.3])
    for backend in ("cpu", "vulkan"):
        first = None
        for f, up in ((forward, (0, 0, 1)), (forward * 100, (0, 0, 1)), (forward * 0.01, (0, 0, 10))):
            view = bvhlab.View((0.5, -9.0, 2.5), tuple(f), up, 40.0)
            image, _ = bvhlab.render(scene, bvh, 48, 32, backend=backend, camera=view)
            if first is None:
                first = image
            np.testing.assert_allclose(image, first, atol=1e-4)  # the primary rays' own rounding
    # the placement itself: a unit up, and the same light for up scaled (Camera's default light too)
    camera = bvhlab.Camera((0.5, -9.0, 2.5), (0.0, 0.0, 0.0), (0.0, 0.0, 1.0))
    scaled = bvhlab.Camera((0.5, -9.0, 2.5), (0.0, 0.0, 0.0), (0.0, 0.0, 10.0))
    np.testing.assert_allclose(default_light(scaled).position, _light_beside(camera), rtol=1e-12)
    # far from the origin, a unit forward: rendered (the sky at least), not refused
    far = bvhlab.Scene(triangles=(tris + np.float32(1e8)).astype(np.float32))
    far.light = None
    view = bvhlab.View((1e8, 1e8 - 20.0, 1e8), (0.0, 1.0, 0.0))
    image, _ = bvhlab.render(far, bvhlab.build(far), 8, 6, backend="cpu", camera=view)
    assert np.isfinite(image).all()


def test_a_snapshot_without_a_camera_says_why(tmp_path):
    """The snapshot gave "snapshot failed: AttributeError: 'NoneType' object has no attribute
    'position'" from its child process (a helper's audit); the render's reason now, before any work."""
    import subprocess
    import sys

    path = tmp_path / "far.npz"
    bvhlab.Scene(triangles=_wide_triangle()).save(path)
    done = subprocess.run(
        [sys.executable, "-m", "bvhlab", "snapshot", str(path), "--out", str(tmp_path / "s.png")],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert done.returncode == 2 and "Traceback" not in done.stderr, done.stderr
    assert "the default camera, which frames the whole scene, cannot be placed" in done.stderr
    assert not (tmp_path / "s.png").exists()


def test_the_default_camera_frames_a_tiny_scene_as_a_large_one():
    """A knot 1.6e-8 across (scenes build down to ~2e-10) was framed from an absolute 1e-6 minimum
    radius: 0 of its pixels showed it (a helper's audit). The same picture at every scale now."""
    from bvhlab.library import procedural

    def shown(span: float) -> int:
        scene = bvhlab.Scene(triangles=procedural.torus_knot(2000) * np.float32(span / 4))
        image, _ = bvhlab.render(scene, bvhlab.build(scene), 80, 60, backend="cpu")
        return int((np.abs(image[..., :3] - np.float32(scene.sky)).max(-1) > 1e-3).sum())

    large = shown(1.0)
    assert large > 300
    for span in (1e-9, 1.6e-8, 1.6e-7):
        assert shown(span) == large, span
