"""The scene's first point light → `bvhlab.Light`.

Watts → intensity. bvhlab's `Light.intensity` is a unitless scale where 1 makes a white Lambertian
surface facing the light show its full base colour. A Blender point light of power P watts
delivers an irradiance of about P / (4π d²) at distance d, and a Lambertian surface reflects
1/π of it, so the export sets

    intensity = P / (4 π² d²),  d = median distance from the light to the exported primitives

(d at least 1e-3): a typical surface of the scene is lit about as brightly as in Blender. The
median keeps one object next to the light from deciding it. Blender's default 1000 W light,
7.4 m from the default cube, becomes ≈ 0.46. d is measured once and kept by whoever renders
frame after frame (LiveScene.light_distance; an animation's frames in the add-on): measured every
frame, a ball rolling away from a static light darkened the static floor under it 0.416 → 0.084
over four frames. The add-on's Light Distance fixes d in the scene (export_scene(light_distance=)),
so that render jobs starting at other frames (a render farm's chunks) light alike.
"""

from __future__ import annotations

import math
import warnings

import numpy as np

from ..scene import Light
from .errors import ExportWarning, naming
from .scope import visibility


def first_light(depsgraph, view_layer):
    """The first visible light object (scope.visibility), evaluated: a point light by name, else
    another kind by name; None when the scene has none. (A pass over every object of the
    depsgraph: 15 ms for 20,000.)"""
    visible = visibility(depsgraph)
    lights = sorted(
        (obj for obj in depsgraph.objects if obj.type == "LIGHT" and visible(obj.original, view_layer)),
        key=lambda obj: (obj.data.type != "POINT", obj.name),
    )
    return lights[0] if lights else None


def gather_light(
    depsgraph, view_layer, primitive_points: np.ndarray, distance: float | None = None, light=None
) -> tuple[Light, float | None] | None:
    """The first visible point light (first_light; another kind of light stands in, at its
    position, with an ExportWarning), or the evaluated light object `light` where the caller knows
    it, and the distance d its intensity is calibrated by; None when the scene has no visible
    light. d is `distance` where given, else the median distance to `primitive_points` (N,3), a
    sample of primitive centres (None where there are none: the intensity is then that of d = 1,
    and the next call measures)."""
    if light is None:
        light = first_light(depsgraph, view_layer)
        if light is None:
            return None
    if light.data.type != "POINT":
        warnings.warn(
            f"no point light; light '{light.name}' ({light.data.type.lower()}) is used as a "
            f"point light at its position",
            ExportWarning,
            stacklevel=2,
        )
    position = np.array(light.matrix_world.translation, np.float64)
    measured = distance
    if measured is None and len(primitive_points):
        # a float32, as a Blender float property keeps it (the add-on's Light Distance): a distance
        # measured and one measured, stored and read back light alike
        measured = float(np.float32(np.median(np.linalg.norm(primitive_points - position, axis=1))))
    # nothing to measure (no geometry yet): d = 1 for now, and None kept, so the next sync measures
    intensity = intensity_from_watts(light.data.energy, 1.0 if measured is None else measured)
    with naming("light", light.name):
        return Light(tuple(position), tuple(light.data.color), intensity), measured


def saved_light_distance(blender_scene) -> float | None:
    """The add-on's Light Distance saved in `blender_scene` (scene.bvhlab.light_distance), or None
    where it is 0 or was never set: through the registered property where the add-on is enabled,
    else from the values Blender keeps for an unregistered property group (a .blend read by the
    CLI: among the scene's ID properties up to 4.x, its system properties from 5.0)."""
    settings = getattr(blender_scene, "bvhlab", None)
    if settings is not None and hasattr(settings, "light_distance"):
        value = settings.light_distance
    else:
        system = getattr(blender_scene, "bl_system_properties_get", None)
        stores = ([system()] if system is not None else []) + [blender_scene]
        groups = [store.get("bvhlab") for store in stores if store is not None]
        value = next((g.get("light_distance") for g in groups if hasattr(g, "get")), None)
    if not isinstance(value, (int, float)) or isinstance(value, bool):
        return None
    return float(value) if math.isfinite(value) and value > 0 else None


def intensity_from_watts(watts: float, distance: float) -> float:
    """The mapping in this module's docstring."""
    return max(float(watts), 0.0) / (4 * math.pi**2 * max(distance, 1e-3) ** 2)
