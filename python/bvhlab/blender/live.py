"""A `bvhlab.Scene` kept in step with a Blender depsgraph between frames (the render engine's scene).

The first `LiveScene.sync` reads everything, as `export_scene` does (which is one sync of a new
LiveScene: one export code path). Later syncs read again only what the depsgraph reports as
changed since the last evaluation (`depsgraph.updates`, valid inside RenderEngine.update /
view_update and after `depsgraph.update()`):

- an object whose geometry changed (`is_updated_geometry`, or its mesh data-block updated) is read
  again (vertices, triangles, material slots);
- an object that only moved is placed again from the vertices read before (no mesh read);
- a material reported as updated is read again; the others come from the last sync;
- camera, light and sky are gathered every sync (a few attribute reads).

Each sync returns a `SyncReport` saying what changed, so a caller can keep its tree (nothing moved),
refit it (same primitives in the same order, moved) or rebuild it (anything else).
"""

from __future__ import annotations

import copy
import warnings
from dataclasses import dataclass, field

import bpy
import numpy as np

from ..scene import Scene, default_camera, default_light
from .camera import gather_camera
from .errors import ExportError, SubstituteWarning
from .light import gather_light
from .material_table import MaterialTable, map_slots
from .mesh import CONVERTIBLE_TYPES, MeshData, read_mesh
from .scope import instances_in_scope
from .sphere import is_analytic_sphere, place_sphere, sphere_bounds
from .world import gather_sky

#: Object types that can have primitives (meshes, and what converts to a mesh).
GEOMETRY_TYPES = CONVERTIBLE_TYPES | {"MESH"}


@dataclass
class SyncReport:
    """What one sync found. `geometry`: the triangles or spheres differ from the last sync;
    `refittable`: they differ only in position (same primitives, same order: a refit can follow);
    `materials`: the material table or the primitives' materials differ."""

    full: bool = False
    objects_read: int = 0
    objects_moved: int = 0
    materials_read: int = 0
    geometry: bool = False
    refittable: bool = False
    materials: bool = False


@dataclass
class SyncTotals:
    """Counts over a LiveScene's life (tests count exports with them)."""

    syncs: int = 0
    full_syncs: int = 0
    objects_read: int = 0
    objects_moved: int = 0
    materials_read: int = 0

    def add(self, report: SyncReport) -> None:
        self.syncs += 1
        self.full_syncs += report.full
        self.objects_read += report.objects_read
        self.objects_moved += report.objects_moved
        self.materials_read += report.materials_read


@dataclass
class _Part:
    """One object or instance as last read: its mesh (or a sphere's object-space bounds), the world
    matrix it was placed with, and the placed primitives (triangles (T,3,3) or a sphere (4,))."""

    mesh: MeshData | None
    bounds: np.ndarray | None
    matrix: np.ndarray
    placed: np.ndarray

    @property
    def shape(self) -> tuple:
        return ("sphere",) if self.mesh is None else ("mesh", self.mesh.triangle_count)

    def moved_to(self, matrix: np.ndarray, name: str) -> _Part:
        if self.mesh is None:
            assert self.bounds is not None  # a sphere keeps its object-space bounds
            return _Part(None, self.bounds, matrix, place_sphere(self.bounds, matrix, name))
        return _Part(self.mesh, None, matrix, self.mesh.world_triangles(matrix, name))


def _read_part(obj, matrix: np.ndarray, name: str) -> _Part:
    if obj.type == "MESH" and is_analytic_sphere(obj):
        bounds = sphere_bounds(obj)
        return _Part(None, bounds, matrix, place_sphere(bounds, matrix, name))
    mesh = read_mesh(obj, name)
    return _Part(mesh, None, matrix, mesh.world_triangles(matrix, name))


@dataclass
class _Dirty:
    """Names (original, full) of what depsgraph.updates reports; `everything` on the first sync."""

    everything: bool = False
    objects: set = field(default_factory=set)
    meshes: set = field(default_factory=set)
    materials: set = field(default_factory=set)

    @classmethod
    def from_updates(cls, depsgraph) -> _Dirty:
        dirty = cls()
        for update in depsgraph.updates:
            data = update.id.original
            if isinstance(data, bpy.types.Object) and update.is_updated_geometry:
                dirty.objects.add(data.name_full)
            elif isinstance(data, bpy.types.Mesh) and update.is_updated_geometry:
                dirty.meshes.add(data.name_full)
            elif isinstance(data, (bpy.types.Material, bpy.types.ShaderNodeTree)):
                dirty.materials.add(data.name_full)
        return dirty

    def geometry_of(self, obj, key: tuple) -> bool:
        if self.everything or key[0] in self.objects or key[1] in self.objects:
            return True
        data = getattr(obj.original, "data", None)
        return data is not None and data.name_full in self.meshes


class LiveScene:
    """The scene of one depsgraph, kept between syncs. `scene` is the last exported bvhlab.Scene
    (a new object after every sync that changed anything; arrays that did not change are shared
    with the previous one). `totals` counts reads over the LiveScene's life."""

    def __init__(self, scope: str = "visible", *, require_camera: bool = True):
        self.scope, self.require_camera = scope, require_camera
        self.scene: Scene | None = None
        self.totals = SyncTotals()
        self._parts: dict[tuple, _Part] = {}
        self._materials: dict = {}  # material name → bvhlab.Material, as last read

    def sync(self, depsgraph, blender_scene=None, view_layer=None) -> SyncReport:
        """Bring `scene` up to date with the evaluated depsgraph. Raises ExportError (see
        export_scene); on an error the previous scene and cache stay as they were."""
        blender_scene = blender_scene or depsgraph.scene
        view_layer = view_layer or depsgraph.view_layer
        full = self.scene is None
        dirty = _Dirty(everything=True) if full else _Dirty.from_updates(depsgraph)
        known = {k: v for k, v in self._materials.items() if k not in dirty.materials}
        table = MaterialTable(known)
        parts, report = self._walk(depsgraph, view_layer, dirty, table)
        report.full = full
        arrays = self._arrays(parts, table, report)
        report.materials_read = table.reads
        scene = self._make_scene(arrays, table, blender_scene, depsgraph, report)
        light = gather_light(depsgraph, view_layer, _primitive_sample(scene))
        if light is None:
            warnings.warn(
                f"scene '{blender_scene.name}' has no visible light; using a default point light near the camera",
                SubstituteWarning,
                stacklevel=2,
            )
            assert scene.camera is not None  # _make_scene always gives the scene a camera
            light = default_light(scene.camera)
        scene.light = light
        self.scene, self._materials = scene, table.known
        self._parts = {key: part for key, (part, _) in parts.items()}
        self.totals.add(report)
        return report

    def _walk(self, depsgraph, view_layer, dirty: _Dirty, table: MaterialTable) -> tuple[dict, SyncReport]:
        """Every object in scope, read again when dirty or new, placed again when moved; in the
        depsgraph's order (the order export_scene has always used). Each part comes with the
        material table index of each of its slots, read here: an instance's object is valid only
        while it is the depsgraph iterator's current item (geometry-nodes and nested collection
        instances crashed Blender when their slots were read after the loop had moved on)."""
        parts, report = {}, SyncReport()
        for item in instances_in_scope(depsgraph, view_layer, self.scope):
            if item.obj.type not in GEOMETRY_TYPES:  # cameras, lights, empties: no primitives
                continue
            old = self._parts.get(item.key)
            sphere = item.obj.type == "MESH" and is_analytic_sphere(item.obj)
            if old is None or (old.mesh is None) != sphere or dirty.geometry_of(item.obj, item.key):
                part = _read_part(item.obj, item.matrix, item.name)
                report.objects_read += 1
            elif not np.array_equal(old.matrix, item.matrix):
                part = old.moved_to(item.matrix, item.name)
                report.objects_moved += 1
            else:
                part = old
            has_primitives = part.mesh is None or part.mesh.triangle_count > 0
            parts[item.key] = (part, table.slot_indices(item.obj) if has_primitives else None)
        return parts, report

    def _arrays(self, parts: dict, table: MaterialTable, report: SyncReport) -> dict:
        """Triangles, spheres and their material indices, in walk order (the material table is
        rebuilt in that order every sync); the previous geometry arrays when nothing moved."""
        triangles, tri_material, spheres, sphere_material = [], [], [], []
        for part, slot_table in parts.values():
            if part.mesh is None:
                spheres.append(part.placed)
                sphere_material.append(slot_table[0])
            elif part.mesh.triangle_count:
                triangles.append(part.placed)
                tri_material.append(map_slots(slot_table, part.mesh.slots))
        if not triangles and not spheres:
            raise ExportError(_nothing_in_scope(self.scope))
        same_order = list(self._parts) == list(parts)
        report.geometry = bool(self.scene is None or report.objects_read or report.objects_moved or not same_order)
        report.refittable = (
            report.geometry
            and same_order
            and [p.shape for p in self._parts.values()] == [p.shape for p, _ in parts.values()]
        )
        previous = self.scene
        arrays = {
            "tri_material": np.concatenate(tri_material) if tri_material else np.zeros(0, np.int32),
            "sphere_material": np.array(sphere_material, np.int32),
        }
        if report.geometry:
            arrays["triangles"] = np.concatenate(triangles) if triangles else np.zeros((0, 3, 3), np.float32)
            arrays["spheres"] = np.array(spheres, np.float32).reshape(-1, 4)
        else:
            assert previous is not None  # no geometry change means there was a scene before
            arrays["triangles"], arrays["spheres"] = previous.triangles, previous.spheres
        report.materials = previous is None or not (
            previous.materials == table.materials
            and np.array_equal(previous.tri_material, arrays["tri_material"])
            and np.array_equal(previous.sphere_material, arrays["sphere_material"])
        )
        return arrays

    def _make_scene(self, arrays: dict, table: MaterialTable, blender_scene, depsgraph, report) -> Scene:
        camera = self._camera(blender_scene, depsgraph)
        sky = gather_sky(blender_scene)
        previous = self.scene
        if previous is not None and not report.geometry and not report.materials:
            scene = copy.copy(previous)  # the same arrays: renderers keep what they uploaded
            scene.camera = camera if camera is not None else default_camera(scene.bounds())
            r, g, b = (float(c) for c in sky)
            scene.sky = (r, g, b)
            return scene
        return Scene(
            triangles=arrays["triangles"],
            spheres=arrays["spheres"],
            materials=table.materials,
            tri_material=arrays["tri_material"],
            sphere_material=arrays["sphere_material"],
            camera=camera,
            sky=sky,
        )

    def _camera(self, blender_scene, depsgraph):
        try:
            return gather_camera(blender_scene, depsgraph)
        except ExportError as error:
            if self.require_camera:
                raise
            warnings.warn(f"{error}; using a default camera that frames the geometry", SubstituteWarning, stacklevel=3)
            return None


def _primitive_sample(scene: Scene, size: int = 4096) -> np.ndarray:
    """Centres of about `size` primitives, evenly strided (deterministic), as float64 (N,3)."""
    triangles = scene.triangles[:: max(1, len(scene.triangles) // size)].mean(axis=1)
    spheres = scene.spheres[:: max(1, len(scene.spheres) // size), :3]
    return np.concatenate([triangles, spheres]).astype(np.float64)


def _nothing_in_scope(scope: str) -> str:
    if scope == "selected":
        return "no mesh in scope: no selected object has geometry (select meshes, or use scope 'visible')"
    return "no mesh in scope: no visible object has geometry (add a mesh or unhide one)"
