"""What a render uses when the scene does not say: the one definition lives in C++
(core_cpp/include/bvhlab/render_defaults.h); this module hands it to Python (`Scene`, `render`)."""

from __future__ import annotations

from . import _core

#: The atmosphere colour of rays that hit nothing (report §2.1): a soft blue.
SKY: tuple[float, float, float] = tuple(_core.DEFAULT_SKY)
#: Matte white: r, g, b, reflective, transparent, ior, holdout, hidden rays (the core's material row).
MATERIAL: tuple[float, ...] = tuple(_core.DEFAULT_MATERIAL)
#: Vertical field of view of the default camera, degrees.
FOV_Y: float = float(_core.DEFAULT_FOV_Y)


def camera_placement(bounds=None) -> tuple[tuple, tuple, tuple, float]:
    """(position, target, up, fov_y) of the camera that frames `bounds` = (lo, hi): looking at the
    centre from the front-upper diagonal (Z up, front = -Y as in Blender), far enough back that the
    bounding sphere fits the view. Without bounds: the fallback camera."""
    if bounds is None:
        return _core.default_camera((0.0, 0.0, 0.0), (0.0, 0.0, 0.0), True)
    lo, hi = bounds
    return _core.default_camera(tuple(float(x) for x in lo), tuple(float(x) for x in hi))


def light_position(position, target, up) -> tuple[float, float, float]:
    """The default point light for a camera: a little above and to the right of it."""
    return tuple(
        _core.default_light_position(tuple(map(float, position)), tuple(map(float, target)), tuple(map(float, up)))
    )
