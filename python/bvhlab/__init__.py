"""bvhlab: bounding volume hierarchies over triangles and spheres, with the split methods of
Sandén's report (median, mean, binned SAH) and more (midpoint, full-sweep SAH, LBVH, refit)."""

import atexit as _atexit

from . import _as_main  # isort: skip  (first: Ctrl-C while `python -m bvhlab` loads the rest)
from . import _core
from ._core import BuildCancelled
from .build_config import AXES, METHODS, BuildConfig
from .bvh import NODE_DTYPE, Bvh, build
from .inspect.tree_file import load_bvh
from .instanced import InstancedBvh
from .optimize import OptimizeConfig, OptimizeStats
from .png import save_png
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

#: At exit, long calls still running on other threads (a daemon thread's build or render) park,
#: without the GIL, until the process ends, and Python finalizes once they have (up to 10 s): a
#: thread that took the GIL back during finalization was ended in a way that aborted the process
#: (Blender quit while one rendered).
_atexit.register(_core._finish_long_calls, 10.0)

_as_main.loaded()  # (where an import above fails, its ImportError ends `python -m` anyway)
