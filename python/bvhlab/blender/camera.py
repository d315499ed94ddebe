"""The scene camera → `bvhlab.Camera`, framed as Cycles frames Blender's camera: perspective and
orthographic with sensor fit and lens shift, the render's aspect with its pixel aspect, clipping,
depth of field (thin lens), and the panoramic equirectangular and fisheye equidistant projections;
and each view of a stereo or multi-view render (StereoView: the eye's matrix and lens shift as
the render engine gives them, the view's own camera in multi-view).

Cycles' own conversion is the model (intern/cycles/blender/camera.cpp: blender_camera_from_object,
blender_camera_viewplane, blender_camera_focal_distance); bvhlab.Camera's conventions are those of
Blender's sensor fit Auto (core_cpp/include/bvhlab/camera.h), so other fits are converted here.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass

import numpy as np

from ..scene import Camera
from .errors import ExportError, ExportWarning

#: Blender's panorama types bvhlab renders, as bvhlab.Camera's projection.
PANORAMAS = {"EQUIRECTANGULAR": "equirectangular", "FISHEYE_EQUIDISTANT": "fisheye"}


def gather_camera(scene, depsgraph, *, view=None, camera=None, size: tuple[int, int] | None = None) -> Camera:
    """Position and orientation from the evaluated camera's world matrix (it looks along its -Z,
    its +Y is up; scale ignored, as Cycles clears it, but not the axes' signs: a matrix of negative
    determinant mirrors the image, as in Cycles; look_at is ahead along the view axis), and
    its lens for the scene's render resolution. `view` (a StereoView): one view of a stereo or
    multi-view render instead, as the render engine gives it. `camera`: the object rendered through
    instead of the scene camera (RenderEngine.camera_override: a Sequencer strip's camera); `size`:
    the frame's pixels where they are not the scene's (RenderEngine.resolution_x, _y: a scene
    rendered by another's compositor is rendered at that scene's size). Raises ExportError when
    there is no usable camera or it is of a kind bvhlab does not render."""
    camera = (camera or scene.camera) if view is None else view.camera
    if camera is None:
        raise ExportError(f"scene '{scene.name}' has no camera: add one and make it the active camera")
    evaluated = camera.evaluated_get(depsgraph)  # animation and drivers applied
    matrix = evaluated.matrix_world if view is None else view.matrix
    position, forward, up, mirrored = _placement(camera.name, np.array(matrix, np.float64))
    # look_at far enough ahead to differ from the position in float32 (the tracer's precision)
    ahead = max(1.0, float(np.abs(position).max()) * 2.0**-10)
    shift_x = None if view is None else view.shift_x
    data = evaluated.data if camera.type == "CAMERA" else stand_in_lens(evaluated)
    lens = lens_fields(scene, data, camera.name, position, forward, shift_x=shift_x, size=size)
    lens["mirrored"] = mirrored
    try:
        return Camera(tuple(position), tuple(position + forward * ahead), tuple(up), **lens)
    except ValueError as error:
        raise ExportError(f"camera '{camera.name}': {error}") from None


@dataclass(frozen=True)
class _NoDepthOfField:
    use_dof: bool = False


@dataclass(frozen=True)
class StandInLens:
    """The lens Blender's renderers give a scene camera that is not a camera (an empty, a light,
    any object: Cycles' blender_camera_init defaults, a light's cone as its field of view;
    stand_in_lens), with the fields of Blender's camera data that lens_fields reads."""

    lens: float = 50.0
    type: str = "PERSP"
    sensor_fit: str = "AUTO"
    sensor_width: float = 36.0
    sensor_height: float = 24.0
    shift_x: float = 0.0
    shift_y: float = 0.0
    clip_start: float = 1e-5
    clip_end: float = 1e5
    ortho_scale: float = 1.0
    dof: _NoDepthOfField = _NoDepthOfField()


#: The spot size every light keeps, spot or not (Blender's default, 45°): what a point, sun or area
#: light as the camera is framed by. One that was a spot light before keeps its own, which bpy
#: does not show on other kinds of light.
DEFAULT_SPOT_SIZE = math.radians(45.0)


def stand_in_lens(obj) -> StandInLens:
    """The lens of a scene camera `obj` (evaluated) that is not a camera, as Cycles renders it
    (blender_camera_from_object): any light's focal length is 16 / tan(spot size / 2) (a spot
    light's own size, DEFAULT_SPOT_SIZE for the others: a point light was given 50 mm, not
    Cycles' 38.6: review); anything else has the focal length of compat.NON_CAMERA_LENS_MM."""
    from .compat import NON_CAMERA_LENS_MM

    data = obj.data
    if obj.type == "LIGHT" and data is not None:
        size = data.spot_size if data.type == "SPOT" else DEFAULT_SPOT_SIZE
        lens = 16.0 / math.tan(size * 0.5)
        if lens > 0:
            return StandInLens(lens=lens)
    return StandInLens(lens=NON_CAMERA_LENS_MM)


@dataclass(frozen=True)
class StereoView:
    """One view of a stereo (Output ▸ Stereoscopy) or multi-view render, as Blender's render
    engine gives it (RenderEngine.camera_model_matrix and camera_shift_x with the view active,
    as Cycles' blender_camera_from_object takes them): the camera object whose lens the view uses
    (multi-view: the camera of the view's suffix), its world matrix for the view (an eye's
    interocular offset, toe-in) and its horizontal lens shift (off-axis convergence)."""

    camera: object
    matrix: object
    shift_x: float


def view_camera_object(scene, view_name: str, camera=None):
    """The camera a view of a multi-view render sees through: the scene camera's (or `camera`'s, a
    RenderEngine.camera_override) name with its view suffix (the longest of the views' that it ends
    with) replaced by this view's, where such an object exists in the scene (Blender's
    camera_multiview_advanced); that camera otherwise, and always in Stereo 3D."""
    render, camera = scene.render, camera or scene.camera
    views = render.views
    if camera is None or render.views_format != "MULTIVIEW" or view_name not in views:
        return camera
    name = camera.name
    suffixes = [v.camera_suffix for v in views if v.camera_suffix and name.endswith(v.camera_suffix)]
    if not suffixes:
        return camera
    prefix = name[: len(name) - len(max(suffixes, key=len))]
    found = scene.objects.get(prefix + views[view_name].camera_suffix)
    return found if found is not None and found.type == "CAMERA" else camera


def _a(noun: str) -> str:
    """`noun` after its indefinite article ("an equiangular cubemap face", "a mirror ball")."""
    return ("an " if noun[:1] in "aeiou" else "a ") + noun


def _placement(name: str, matrix: np.ndarray):
    """(position, unit forward, unit up, mirrored) of a camera's world matrix: mirrored where its
    axes are left-handed (a scale of -1 on one of them, the camera's own or a parent's), which
    Cycles keeps (transform_clear_scale normalises each axis, its sign kept)."""
    z_length, y_length = np.linalg.norm(matrix[:3, 2]), np.linalg.norm(matrix[:3, 1])
    if not (np.isfinite(matrix).all() and z_length > 0 and y_length > 0):
        raise ExportError(
            f"camera '{name}' has no usable orientation (a scale of 0, or a location, rotation "
            f"or scale that is not a number)"
        )
    mirrored = bool(np.linalg.det(matrix[:3, :3]) < 0)
    axes = matrix[:3, :3] / np.linalg.norm(matrix[:3, :3], axis=0).clip(1e-300)
    if np.abs(np.triu(axes.T @ axes, 1)).max() > _SHEARED:
        warnings.warn(
            f"camera '{name}' is sheared (a parent scales it unevenly along axes it is turned "
            "against): Blender renders through its slanted axes, bvhlab through square ones along "
            "its view and up axes, so the image is framed differently",
            ExportWarning,
            stacklevel=3,
        )
    return matrix[:3, 3], -matrix[:3, 2] / z_length, matrix[:3, 1] / y_length, mirrored


#: The largest |cosine| between two of a camera's axes (normalised) taken as square: a float32
#: matrix's rounding stays far below it, a shear that moves the image by a pixel far above.
_SHEARED = 1e-4


def render_size(render) -> tuple[int, int]:
    """The rendered frame's pixels: the resolution at its percentage, rounded down as Blender's
    BKE_render_resolution does."""
    return (
        render.resolution_x * render.resolution_percentage // 100,
        render.resolution_y * render.resolution_percentage // 100,
    )


def lens_fields(
    scene, data, name: str, position=None, forward=None, *, shift_x: float | None = None, size=None
) -> dict:
    """bvhlab.Camera's keyword fields (bvhlab.scene.Lens) for Blender camera data `data` rendered
    at the scene's resolution (or `size`, (width, height) in pixels, where given: its aspect fits
    the sensor); `shift_x` in Blender's units stands for the data's (a stereo view's shift: its lens
    shift and the off-axis convergence's)."""
    render = scene.render
    width, height = size or render_size(render)
    aspect = (max(width, 1) * render.pixel_aspect_x) / (max(height, 1) * render.pixel_aspect_y)
    fields: dict = {"clip_start": data.clip_start, "clip_end": data.clip_end}
    if render.pixel_aspect_x != render.pixel_aspect_y:  # else the image's own, at any size it is rendered
        fields["aspect"] = aspect
    shift = (data.shift_x if shift_x is None else float(shift_x), data.shift_y)
    if data.type == "PANO":
        fields.update(_panorama(data, name, shift))
    elif data.type in ("PERSP", "ORTHO"):
        fields.update(_view_plane(data, aspect, shift))
    else:
        raise ExportError(f"camera '{name}' is of type {data.type}, which bvhlab does not render")
    fields.update(_depth_of_field(data, name, position, forward))
    return fields


def _view_plane(data, aspect: float, shift: tuple[float, float]) -> dict:
    """Perspective or orthographic: Cycles' blender_camera_viewplane. The sensor (or ortho_scale)
    spans the fitted side, lens shift is in fractions of it; bvhlab takes the vertical field of
    view, ortho_scale and shift along the larger side (sensor fit Auto)."""
    fit = data.sensor_fit
    horizontal = aspect > 1 if fit == "AUTO" else fit == "HORIZONTAL"  # Cycles: xratio > yratio
    sensor = data.sensor_height if fit == "VERTICAL" else data.sensor_width
    fitted = data.ortho_scale if data.type == "ORTHO" else sensor / data.lens  # the fitted side's extent
    plane_width, plane_height = (fitted, fitted / aspect) if horizontal else (fitted * aspect, fitted)
    larger = max(plane_width, plane_height)
    fields = {"shift_x": shift[0] * fitted / larger, "shift_y": shift[1] * fitted / larger}
    if data.type == "ORTHO":
        return {**fields, "projection": "orthographic", "ortho_scale": larger}
    return {**fields, "projection": "perspective", "fov_y": math.degrees(2 * math.atan(plane_height / 2))}


def _panorama(data, name: str, shift: tuple[float, float]) -> dict:
    """Equirectangular or fisheye equidistant; the panorama settings are the camera's own from
    Blender 4.0 (data.panorama_type), Cycles' before (data.cycles.panorama_type)."""
    settings = data if hasattr(data, "panorama_type") else getattr(data, "cycles", None)
    kind = getattr(settings, "panorama_type", None)
    if settings is None or kind not in PANORAMAS:
        raise ExportError(
            f"camera '{name}' is {_a(str(kind).replace('_', ' ').lower())} panorama; bvhlab renders the "
            f"equirectangular and fisheye equidistant panoramas only"
        )
    fields = {"projection": PANORAMAS[kind], "shift_x": shift[0], "shift_y": shift[1]}
    if kind == "EQUIRECTANGULAR":
        fields["latitude"] = (math.degrees(settings.latitude_min), math.degrees(settings.latitude_max))
        fields["longitude"] = (math.degrees(settings.longitude_min), math.degrees(settings.longitude_max))
    else:
        fields["fisheye_fov"] = math.degrees(settings.fisheye_fov)
    return fields


def _focus_point(dof) -> np.ndarray:
    """Where the focus object is: its origin, or the head of its pose bone named by the focus
    subtarget (an armature's bone, as Cycles' blender_camera_focal_distance takes it)."""
    obj = dof.focus_object
    matrix = np.array(obj.matrix_world, np.float64)
    bone_name = getattr(dof, "focus_subtarget", "")
    bone = obj.pose.bones.get(bone_name) if bone_name and obj.pose is not None else None
    if bone is not None:
        matrix = matrix @ np.array(bone.matrix, np.float64)
    return matrix[:3, 3]


def _depth_of_field(data, name: str, position, forward) -> dict:
    """A thin lens as Cycles makes it (blender_camera_from_object): its radius from the focal
    length and f-stop (orthographic: from the f-stop alone), in scene units; the focus distance,
    or the focus object's (or its bone's) distance along the view axis (blender_camera_focal_distance)."""
    dof = data.dof
    if not dof.use_dof:
        return {}
    fstop = max(dof.aperture_fstop, 1e-5)
    radius = 1.0 / (2 * fstop) if data.type == "ORTHO" else data.lens * 1e-3 / (2 * fstop)
    focus = dof.focus_distance
    if dof.focus_object is not None and position is not None:
        target = _focus_point(dof)
        focus = abs(float(np.dot(forward, target - position)))
    if dof.aperture_blades >= 3 or dof.aperture_ratio != 1.0:
        warnings.warn(
            f"camera '{name}': the depth of field's bokeh is a disc (aperture blades and ratio are ignored)",
            ExportWarning,
            stacklevel=3,
        )
    return {"aperture_radius": radius, "focus_distance": max(focus, 1e-6)}
