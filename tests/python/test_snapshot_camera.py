"""`bvhlab snapshot` frames a scene as the tracer does (probe: it drew every camera as an unshifted
perspective one, so an orthographic or shifted camera's snapshot showed another view): a point on
the primary ray of a pixel (trace_pixel, the tracer's own camera code) projects, through the
snapshot's matrix, to that pixel's centre, for each lens setting the raster draws; the panoramas,
which no matrix draws, are refused before any work."""

import numpy as np
import pytest

import bvhlab
from bvhlab.cli import main
from bvhlab.inspect.ray_record import trace_pixel
from bvhlab.snapshot.raster import camera_matrix

EYE, TARGET = (1.0, -8.0, 2.0), (0.0, 0.0, 0.0)
LENSES = {
    "perspective": {},
    "shifted": {"shift_x": 0.2, "shift_y": -0.1},
    "orthographic, shifted": {"projection": "orthographic", "ortho_scale": 6.0, "shift_x": 0.1, "shift_y": 0.3},
    "wide image plane": {"aspect": 2.5},
    "tall orthographic": {"projection": "orthographic", "ortho_scale": 6.0, "aspect": 0.5},
    "region of the frame": {"region": (0.25, 0.1, 0.75, 0.6), "shift_x": 0.1},
    "mirrored": {"mirrored": True, "shift_x": 0.1},
}


@pytest.mark.parametrize("lens", list(LENSES))
def test_a_pixels_ray_projects_to_that_pixel(lens):
    width, height = 64, 40
    rng = np.random.default_rng(1)
    scene = bvhlab.Scene(
        triangles=(rng.random((50, 3, 3)) * 4 - 2).astype(np.float32), camera=bvhlab.Camera(EYE, TARGET, **LENSES[lens])
    )
    bvh = bvhlab.build(scene)
    matrix = camera_matrix(scene.camera, width / height, 0.01, 100.0).astype(np.float64)
    for x, y in [(0, 0), (width - 1, 0), (0, height - 1), (width - 1, height - 1), (width // 2, height // 3)]:
        record = trace_pixel(scene, bvh, x, y, width=width, height=height)
        point = np.array(record.origin) + 5.0 * np.array(record.direction)
        clip = matrix @ np.append(point, 1.0)
        ndc = clip[:3] / clip[3]
        at = ((ndc[0] + 1) / 2 * width, (1 - ndc[1]) / 2 * height)
        np.testing.assert_allclose(at, (x + 0.5, y + 0.5), atol=1e-3, err_msg=f"{lens}: pixel {(x, y)}")


def test_a_panoramic_camera_is_refused_before_any_work(tmp_path, capsys):
    tris = np.random.default_rng(2).random((20, 3, 3), dtype=np.float32)
    scene = bvhlab.Scene(triangles=tris, camera=bvhlab.Camera(EYE, TARGET, projection="equirectangular"))
    scene.save(tmp_path / "pano.npz")
    out = tmp_path / "s.png"
    assert main(["snapshot", str(tmp_path / "pano.npz"), "--out", str(out)]) == 2
    assert "its camera is equirectangular; the snapshot draws perspective and orthographic" in capsys.readouterr().err
    assert not out.exists()
