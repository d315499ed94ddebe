"""bvhlab: bounding volume hierarchies over triangles and spheres, with the split methods of
Sandén's report (median, mean, binned SAH) and more (midpoint, full-sweep SAH, LBVH, refit)."""

from ._core import BuildCancelled
from .build_config import AXES, METHODS, BuildConfig
from .bvh import NODE_DTYPE, Bvh, build
from .inspect.tree_file import load_bvh
from .instanced import InstancedBvh
from .optimize import OptimizeConfig, OptimizeStats
from .ray_query import TRAVERSALS
from .render import (
    RenderCancelled,
    Renderer,
    RenderIncomplete,
    RenderJob,
    RenderResult,
    View,
    VulkanUnavailable,
    render,
    save_png,
)
from .render_options import RenderOptions
from .scene import Camera, Light, Material, Scene
from .scene_parts import Rays
from .update import UPDATE_POLICIES, UpdateConfig, UpdateStats

__version__ = "0.1.0"
__all__ = [
    "build",
    "Bvh",
    "load_bvh",
    "InstancedBvh",
    "BuildConfig",
    "BuildCancelled",
    "Scene",
    "UpdateConfig",
    "UpdateStats",
    "UPDATE_POLICIES",
    "OptimizeConfig",
    "OptimizeStats",
    "Camera",
    "Light",
    "Material",
    "Rays",
    "METHODS",
    "AXES",
    "TRAVERSALS",
    "NODE_DTYPE",
    "render",
    "RenderOptions",
    "Renderer",
    "RenderJob",
    "RenderResult",
    "View",
    "RenderCancelled",
    "RenderIncomplete",
    "VulkanUnavailable",
    "save_png",
]
