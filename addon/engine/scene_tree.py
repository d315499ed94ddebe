"""The engine's tree over a scene kept between frames: built once, refit when only transforms moved,
kept when nothing moved (the depsgraph said so, or the arrays are equal)."""

from __future__ import annotations

import time
from dataclasses import asdict, dataclass

import numpy as np

from bvhlab.bvh import (
    DEFAULT_AXIS,
    DEFAULT_BIN_BOUNDS,
    DEFAULT_BINS,
    DEFAULT_MAX_LEAF_SIZE,
    DEFAULT_METHOD,
    DEFAULT_SAH_BLOCK,
)

#: A refit keeps the topology; once objects have moved far, its boxes overlap and tracing slows.
#: Rebuild instead when the refit tree's SAH cost exceeds the built tree's by this factor.
REFIT_LIMIT = 1.5


@dataclass(frozen=True)
class BuildSettings:
    """What a tree depends on besides the geometry: the arguments of `bvhlab.build` that
    scene.bvhlab chooses (its build_kwargs), frozen so that two can be compared. The default is
    the core's defaults."""

    method: str = DEFAULT_METHOD
    bins: int = DEFAULT_BINS
    bin_bounds: str = DEFAULT_BIN_BOUNDS
    axis: str = DEFAULT_AXIS
    max_leaf_size: int = DEFAULT_MAX_LEAF_SIZE
    sah_block: int = DEFAULT_SAH_BLOCK

    @classmethod
    def of(cls, blender_scene) -> BuildSettings:
        return cls(**blender_scene.bvhlab.build_kwargs())


@dataclass(frozen=True)
class TreeUpdate:
    """What `SceneTree.update` did: "built", "refit" or "kept", and how long it took."""

    action: str
    ms: float = 0.0


class SceneTree:
    """A Bvh over the geometry of the scenes given to `update`, and the settings it was built with."""

    def __init__(self):
        self.bvh = None
        self.settings: BuildSettings | None = None
        self._source: tuple = (None, None)  # the triangle and sphere arrays the tree is over
        self._built_sah = 0.0

    def update(
        self, scene, settings: BuildSettings, refittable: bool = False, progress=None, threads: int = 0
    ) -> TreeUpdate:
        """Make the tree fit `scene` (a bvhlab.Scene). `refittable`: the primitives are those of the
        last scene, in the same order, only moved (LiveScene's report). `progress(fraction)`
        returning False cancels a build (bvhlab.BuildCancelled). `threads`: for a build (0: all)."""
        start = time.perf_counter()
        if self.bvh is not None and settings == self.settings:
            if self._same_geometry(scene):
                self._source = (scene.triangles, scene.spheres)
                return TreeUpdate("kept")
            if refittable and self._refit(scene):
                return TreeUpdate("refit", (time.perf_counter() - start) * 1e3)
        self._build(scene, settings, progress, threads)
        return TreeUpdate("built", (time.perf_counter() - start) * 1e3)

    def _same_geometry(self, scene) -> bool:
        triangles, spheres = self._source
        if triangles is scene.triangles and spheres is scene.spheres:
            return True
        return (
            triangles is not None
            and np.array_equal(triangles, scene.triangles)
            and np.array_equal(spheres, scene.spheres)
        )

    def _refit(self, scene) -> bool:
        triangles, spheres = self._source
        if triangles is None or len(triangles) != len(scene.triangles) or len(spheres) != len(scene.spheres):
            return False
        try:
            self.bvh.refit(scene.triangles, scene.spheres)
        except ValueError:  # not the geometry the tree was built over after all: build instead
            return False
        self._source = (scene.triangles, scene.spheres)
        return self.bvh.stats["sah_cost"] <= REFIT_LIMIT * self._built_sah

    def _build(self, scene, settings: BuildSettings, progress, threads: int) -> None:
        import bvhlab

        self.bvh = None  # a cancelled build leaves no stale tree behind
        bvh = bvhlab.build(scene, **asdict(settings), threads=threads, progress=progress)
        self.bvh, self.settings = bvh, settings
        self._source = (scene.triangles, scene.spheres)
        self._built_sah = bvh.stats["sah_cost"]
