"""The moderngl drawing: flat-shaded triangles, instanced spheres, instanced box edges."""

from __future__ import annotations

import math

import numpy as np

MESH_VS = """
#version 330
uniform mat4 mvp;
in vec3 in_position; in vec3 in_normal; in vec3 in_color;
out vec3 normal; out vec3 color;
void main() { gl_Position = mvp * vec4(in_position, 1.0); normal = in_normal; color = in_color; }
"""
SPHERE_VS = """
#version 330
uniform mat4 mvp;
in vec3 in_unit; in vec4 in_sphere; in vec3 in_color;
out vec3 normal; out vec3 color;
void main() { gl_Position = mvp * vec4(in_sphere.xyz + in_sphere.w * in_unit, 1.0); normal = in_unit; color = in_color; }
"""
SHADED_FS = """
#version 330
uniform vec3 light_dir;
in vec3 normal; in vec3 color;
out vec4 frag;
void main() { frag = vec4(color * (0.25 + 0.75 * abs(dot(normalize(normal), light_dir))), 1.0); }
"""
BOX_VS = """
#version 330
uniform mat4 mvp;
in vec3 in_corner; in vec3 in_lo; in vec3 in_hi; in vec3 in_color;
out vec3 color;
void main() { gl_Position = mvp * vec4(mix(in_lo, in_hi, in_corner), 1.0); gl_Position.z -= 1e-4 * gl_Position.w; color = in_color; }
"""
BOX_FS = """
#version 330
in vec3 color; out vec4 frag;
void main() { frag = vec4(color, 1.0); }
"""


def box_corners() -> np.ndarray:
    """The 24 line vertices of a box as 0/1 masks (the same edge order as shaders/tracer/overlay.glsl)."""
    out = []
    for vertex in range(24):
        edge, end = divmod(vertex, 2)
        axis, k = divmod(edge, 4)
        corner = [0, 0, 0]
        corner[axis] = end
        corner[(axis + 1) % 3] = k & 1
        corner[(axis + 2) % 3] = k >> 1
        out.append(corner)
    return np.array(out, np.float32)


def unit_sphere(subdivisions: int = 2) -> np.ndarray:
    """Triangles of a subdivided octahedron on the unit sphere, (N, 3) vertices."""
    v = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]], np.float32)
    tris = [
        v[[a, b, c]]
        for a, b, c in [(0, 2, 4), (2, 1, 4), (1, 3, 4), (3, 0, 4), (2, 0, 5), (1, 2, 5), (3, 1, 5), (0, 3, 5)]
    ]
    for _ in range(subdivisions):
        new = []
        for a, b, c in tris:
            ab, bc, ca = (a + b) / 2, (b + c) / 2, (c + a) / 2
            new += [np.array(t) for t in ([a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca])]
        tris = new
    verts = np.concatenate(tris)
    return (verts / np.linalg.norm(verts, axis=1, keepdims=True)).astype(np.float32)


#: The projections the raster draws (the panoramas are no matrix: `bvhlab render` traces them).
RASTER_PROJECTIONS = ("perspective", "orthographic")


def camera_matrix(camera, aspect: float, near: float, far: float) -> np.ndarray:
    """Projection × view (OpenGL conventions) of the tracer's camera (camera.h): perspective or
    orthographic, its lens shift, image-plane aspect (`camera.aspect`, else the frame's `aspect`),
    region of the frame and mirroring, so that the snapshot frames a scene as the render does (it
    drew every camera as an unshifted perspective one: an orthographic camera's snapshot showed
    another view). The image plane: 2·tan(fov_y/2) high at unit distance, or ortho_scale along its
    larger side; aspect times as wide; shifted by fractions of its larger side; the region a part
    of the frame from its top-left corner."""
    projection = getattr(camera, "projection", "perspective")
    if projection not in RASTER_PROJECTIONS:
        raise ValueError(f"the snapshot draws {' and '.join(RASTER_PROJECTIONS)} cameras, not {projection}")
    pos, look, up = (np.array(v, np.float64) for v in (camera.position, camera.look_at, camera.up))
    f = (look - pos) / np.linalg.norm(look - pos)
    r = np.cross(f, up)
    r /= np.linalg.norm(r)
    u = np.cross(r, f)
    if getattr(camera, "mirrored", False):  # the image mirrored left to right, as the tracer's
        r = -r
    view = np.eye(4)
    view[0, :3], view[1, :3], view[2, :3] = r, u, -f
    view[:3, 3] = -view[:3, :3] @ pos
    x0, y0, x1, y1 = getattr(camera, "region", (0.0, 0.0, 1.0, 1.0))
    aspect = getattr(camera, "aspect", None) or aspect * (y1 - y0) / (x1 - x0)  # the whole frame's
    proj = np.zeros((4, 4))
    if projection == "perspective":
        height = 2 * math.tan(math.radians(camera.fov_y) / 2)
        larger = height * max(aspect, 1.0)
    else:
        larger = camera.ortho_scale
        height = larger if aspect < 1 else larger / aspect
    width = height * aspect
    shift = (getattr(camera, "shift_x", 0.0) * larger, getattr(camera, "shift_y", 0.0) * larger)
    if projection == "perspective":  # x_ndc = (x / -z - shift) / (width / 2)
        proj[0, 0], proj[0, 2] = 2 / width, 2 * shift[0] / width
        proj[1, 1], proj[1, 2] = 2 / height, 2 * shift[1] / height
        proj[2, 2], proj[2, 3] = (far + near) / (near - far), 2 * far * near / (near - far)
        proj[3, 2] = -1
    else:  # x_ndc = (x - shift) / (width / 2)
        proj[0, 0], proj[0, 3] = 2 / width, -2 * shift[0] / width
        proj[1, 1], proj[1, 3] = 2 / height, -2 * shift[1] / height
        proj[2, 2], proj[2, 3] = -2 / (far - near), -(far + near) / (far - near)
        proj[3, 3] = 1
    region = np.eye(4)  # the frame's part the image shows: its NDC from the frame's, in clip space
    region[0, 0], region[0, 3] = 1 / (x1 - x0), (1 - 2 * x0) / (x1 - x0) - 1
    region[1, 1], region[1, 3] = 1 / (y1 - y0), 1 - (1 - 2 * y0) / (y1 - y0)
    return (region @ proj @ view).astype(np.float32)


class Rasterizer:
    """Draws one scene many times (different box sets) into an RGBA8 image."""

    def __init__(self, scene, width: int, height: int):
        import moderngl

        try:
            self.ctx = moderngl.create_standalone_context(backend="egl")  # type: ignore[arg-type]  # stubs lag the API
        except Exception as e:  # moderngl raises plain Exceptions when EGL or Mesa is missing
            raise RuntimeError(f"no headless OpenGL (EGL): {e}; install libegl1 libegl-mesa0 libgl1-mesa-dri") from e
        self.ctx.enable(self.ctx.DEPTH_TEST)
        self.size = (width, height)
        self.fbo = self.ctx.simple_framebuffer(self.size, components=4)
        self.scene = scene
        lo, hi = scene.bounds()
        eye = np.array(scene.camera.position)
        far = float(np.linalg.norm(np.maximum(np.abs(lo - eye), np.abs(hi - eye)))) * 2 + 1e-3
        self.mvp = camera_matrix(scene.camera, width / height, far * 1e-4, far)
        light = np.array(scene.light.position if scene.light else scene.camera.position, np.float64) - (lo + hi) / 2
        self.light_dir = (light / np.linalg.norm(light)).astype(np.float32)
        self._geometry = self._make_geometry()
        self._box_program = self.ctx.program(vertex_shader=BOX_VS, fragment_shader=BOX_FS)
        self._corners = self.ctx.buffer(box_corners().tobytes())

    def _make_geometry(self):
        colors = self.scene.material_table()[:, :3]
        vaos: list[tuple] = []  # (program, vertex array, instances or None)
        tris = self.scene.triangles
        if len(tris):
            n = np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0])
            n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-30)
            c = colors[self.scene.tri_material]
            data = np.concatenate([tris, np.repeat(n[:, None], 3, 1), np.repeat(c[:, None], 3, 1)], 2)
            prog = self.ctx.program(vertex_shader=MESH_VS, fragment_shader=SHADED_FS)
            vbo = self.ctx.buffer(np.ascontiguousarray(data, np.float32).tobytes())
            vaos.append(
                (prog, self.ctx.vertex_array(prog, [(vbo, "3f 3f 3f", "in_position", "in_normal", "in_color")]), None)
            )
        if len(self.scene.spheres):
            unit = unit_sphere()
            inst = np.concatenate([self.scene.spheres, colors[self.scene.sphere_material]], 1).astype(np.float32)
            prog = self.ctx.program(vertex_shader=SPHERE_VS, fragment_shader=SHADED_FS)
            vao = self.ctx.vertex_array(
                prog,
                [
                    (self.ctx.buffer(unit.tobytes()), "3f", "in_unit"),
                    (self.ctx.buffer(inst.tobytes()), "4f 3f/i", "in_sphere", "in_color"),
                ],
            )
            vaos.append((prog, vao, len(inst)))
        return vaos

    def draw(self, lo: np.ndarray, hi: np.ndarray, colors: np.ndarray, background=(0.08, 0.08, 0.1)) -> np.ndarray:
        """The scene with the given boxes; returns uint8 (height, width, 4), row 0 at the top."""
        self.fbo.use()
        self.fbo.clear(*background, 1.0, depth=1.0)  # type: ignore[misc, call-arg]  # r, g, b, a, depth
        for prog, vao, instances in self._geometry:
            prog["mvp"].write(self.mvp.T.tobytes())
            prog["light_dir"].value = tuple(self.light_dir)
            vao.render(instances=instances) if instances else vao.render()
        if len(lo):
            self._box_program["mvp"].write(self.mvp.T.tobytes())  # type: ignore[union-attr]
            inst = np.ascontiguousarray(np.concatenate([lo, hi, colors], 1), np.float32)
            buf = self.ctx.buffer(inst.tobytes())
            vao = self.ctx.vertex_array(
                self._box_program,
                [(self._corners, "3f", "in_corner"), (buf, "3f 3f 3f/i", "in_lo", "in_hi", "in_color")],
            )
            vao.render(mode=self.ctx.LINES, instances=len(inst))
            vao.release()
            buf.release()
        image = np.frombuffer(self.fbo.read(components=4), np.uint8).reshape(self.size[1], self.size[0], 4)
        return image[::-1].copy()
