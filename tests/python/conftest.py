import os
from pathlib import Path

import numpy as np
import pytest

# Mesa's shader cache inside the build tree, never in ~/.cache (lavapipe compiles on first use).
_cache = Path(__file__).resolve().parents[2] / "build" / "mesa-cache"
os.environ.setdefault("MESA_SHADER_CACHE_DIR", str(_cache))
os.environ.setdefault("XDG_CACHE_HOME", str(_cache))

from bvhlab.library import procedural


@pytest.fixture(scope="session")
def small_scene():
    """A few hundred triangles and spheres, clustered and scattered."""
    rng = np.random.default_rng(3)
    tris = procedural.random_triangles(400, size=0.15, seed=1)
    tris[:200] = tris[:200] * 0.3 + 0.1  # a dense cluster
    spheres = procedural.random_spheres(60, radius=0.04, seed=2)
    spheres[:, :3] += rng.normal(0, 0.01, (60, 3)).astype(np.float32)
    return np.ascontiguousarray(tris), np.ascontiguousarray(spheres)


@pytest.fixture(scope="session")
def knot_mesh():
    """A real mesh of 60k triangles (bumpy torus knot)."""
    return procedural.torus_knot(60000)
