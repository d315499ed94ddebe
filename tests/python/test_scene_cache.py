"""The renderer's scene cache (bvhlab._render_scene.SceneCache) keyed by what it made the scene of."""

import numpy as np

import bvhlab


def test_a_material_set_while_a_render_reads_the_scene_is_not_cached_under_the_old_key():
    """Another thread sets `scene.materials` while a render reads the scene (simulated: reading
    `sphere_material`, which the cache reads after the materials, sets them, as a writer between
    two reads would). The cache made its key and its scene from two reads: the blue scene stayed
    cached under the red key, and every later render of the red scene was blue (a probe: within
    seconds of a writer thread)."""
    red, blue = [bvhlab.Material((1, 0, 0))], [bvhlab.Material((0, 0, 1))]

    class Racing(bvhlab.Scene):
        armed = False

        def __getattribute__(self, name):
            value = super().__getattribute__(name)
            if name == "sphere_material" and type(self).armed:
                type(self).armed = False
                object.__setattr__(self, "materials", blue)  # the other thread, right after this read
            return value

    tris = np.array([[[-5, -5, 0], [5, -5, 0], [5, 5, 0]], [[-5, -5, 0], [5, 5, 0], [-5, 5, 0]]], np.float32)
    scene = Racing(triangles=tris, materials=red, camera=bvhlab.Camera(position=(0, -1, 10), look_at=(0, 0, 0)))
    bvh = bvhlab.build(scene)
    renderer = bvhlab.Renderer("cpu")

    def colour():
        job = renderer.start(scene, bvh, 4, 4)
        job.run()
        rgb = job.result().color[..., :3].mean((0, 1))
        return "red" if rgb[0] > rgb[2] else "blue"

    Racing.armed = True
    assert colour() in ("red", "blue")  # as the one read of the scene found it
    assert scene.materials == blue and not Racing.armed  # the writer went between
    scene.materials = red  # and back, as the probe's writer left it
    assert colour() == "red"
    scene.materials = blue
    assert colour() == "blue"
