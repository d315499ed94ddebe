"""A `bvhlab.Scene` kept in step with a Blender depsgraph between frames (the render engine's scene).

The first `LiveScene.sync` reads everything, as `export_scene` does (which is one sync of a new
LiveScene: one export code path). Later syncs read again only what the depsgraph reports as
changed since the last evaluation (`depsgraph.updates`, valid inside RenderEngine.update /
view_update and after `depsgraph.update()`):

- an object whose geometry changed (`is_updated_geometry`, or its mesh data-block updated) is read
  again (vertices, triangles, material slots); a mesh shared by instances is read once;
- an object that only moved is placed again from the vertices read before (no mesh read); an
  instance of a shared mesh only changes its transform;
- a material reported as updated is read again; the others come from the last sync;
- camera, light and sky are gathered every sync (a few attribute reads);
- where the updates name only transforms of instances (and of cameras, lights, parents), the
  depsgraph is not walked at all: the moved instances' matrices come from the updates
  (`placed_only.py`, on a move or a frame change); likewise where they name only the geometry of
  objects that are each the one instance of their mesh (an object edited or deformed before):
  only those meshes are read again (20,000 objects: 0.7-1.0 s a sync → 5-13 ms).

Instancing (collection instances, linked duplicates, instancing by vertices or faces, geometry-nodes
instances) becomes meshes and instances of the Scene (`instancing.py`); static objects used once
stay in mesh 0, in world space, as before. Movers (an animated transform, `motion.py`, or an item
seen moving or its mesh changing between two syncs, remembered by its key from then on) get a
mesh and an instance of their own, so that moving them only changes a transform, and editing
them only their own mesh.

Each sync returns a `SyncReport` saying what changed, so a caller can keep its tree (nothing moved),
place its instances again (only instance transforms changed: a new TLAS), refit it (same
primitives in the same order, moved) or rebuild it (anything else).
"""

from __future__ import annotations

import copy
import gc
import warnings

import numpy as np

from ..scene import Scene, default_camera, default_light
from .camera import gather_camera
from .depsgraph_updates import Dirty
from .errors import EmptySceneWarning, ExportError, SubstituteWarning
from .instancing import Item, Layout, SharedMesh, plan, shared_meshes
from .light import first_light, gather_light
from .material_table import MaterialTable
from .mesh import MeshData
from .motion import AnimatedMemo
from .placed_only import MoverIndex, Placing, place_moved, place_reshaped, place_spheres, placing_from_updates
from .primitive_sample import primitive_sample
from .scene_arrays import instances, mesh_zero
from .scope import nothing_in_scope
from .sync_report import SyncReport, SyncTotals
from .walk import LastSync, walk
from .world import gather_sky


class LiveScene:
    """The scene of one depsgraph, kept between syncs. `scene` is the last exported bvhlab.Scene
    (a new object after every sync that changed anything; arrays that did not change are shared
    with the previous one). `totals` counts reads over the LiveScene's life. `instancing`: False
    places every instance's triangles into the world (the flat export of before). `allow_empty`:
    nothing in scope gives a scene of no geometry (a render of the world alone, as other engines
    render it, with an EmptySceneWarning) instead of an ExportError: a render engine's frames (an
    animation whose only mesh is hidden on one frame stopped there, its later frames lost)."""

    def __init__(
        self,
        scope: str = "visible",
        *,
        require_camera: bool = True,
        instancing: bool = True,
        allow_empty: bool = False,
        place_from_updates: bool = True,
    ):
        self.scope, self.require_camera, self.instancing = scope, require_camera, instancing
        self.allow_empty = allow_empty
        #: False: every sync walks the depsgraph, also where only instances moved (placed_only.py;
        #: the tests compare the two)
        self.place_from_updates = place_from_updates
        self.scene: Scene | None = None
        #: The render engine's camera and frame size where they are not the scene's own
        #: (RenderEngine.camera_override, resolution_x and _y: gather_camera), set before a sync.
        self.camera_object = None
        self.frame_size: tuple[int, int] | None = None
        #: The distance the light's intensity is calibrated by (light.py): measured at the first sync
        #: with a light, then kept, so a static light lights static geometry alike on every frame;
        #: None measures it again at the next sync.
        self.light_distance: float | None = None
        self.totals = SyncTotals()
        self._items: dict[tuple, Item] = {}
        self._by_data: dict[int, MeshData] = {}  # mesh data address → mesh, as last read
        self._layout: Layout | None = None
        self._shared: list[SharedMesh] = []
        self._table: MaterialTable | None = None  # the last sync's materials, as read
        self._seen_moving: set[tuple] = set()  # keys of the items seen moving or reshaped (movers from then on)
        self._world = np.zeros((0, 4, 4))  # the items' world matrices, row i the i-th item's
        self._override_key: str | None = None  # the view layer's Material Override when last synced
        self._failed = False  # the last sync raised: the next reads everything
        self._index: MoverIndex | None = None  # the items an update places alone (placed_only.py)
        self._sphere_rows: dict[tuple, int] = {}  # mesh 0's spheres' rows by item key (mesh_zero)
        self._light: tuple[str, str] | None = None  # the last sync's light object: (name, full name)
        self._moved: list[tuple] = []  # the keys of the last sync's items that moved (Item.moved)
        self._frame: tuple | None = None  # the scene's frame and subframe at the last sync
        self._missed = False  # an evaluation went unsynced (missed()): the next sync walks

    def sync(self, depsgraph, blender_scene=None, view_layer=None) -> SyncReport:
        """Bring `scene` up to date with the evaluated depsgraph. Raises ExportError (see
        export_scene); on an error the previous scene and cache stay as they were, and the next
        sync reads everything: the updates this evaluation names are not named again, so an edit
        made while the scene could not be exported (an object out of range) would stay unread."""
        # The walk makes a few objects per item and frees none: the collector ran and re-ran over
        # the whole heap (20,000 objects: 60-90 ms of a 0.55 s sync, and its spread); it runs
        # again afterwards, on what is left.
        collecting = gc.isenabled()
        gc.disable()
        try:
            report = self._sync(depsgraph, blender_scene, view_layer)
        except BaseException:
            self._failed = True
            raise
        finally:
            if collecting:
                gc.enable()
        self._failed = False
        return report

    def _sync(self, depsgraph, blender_scene, view_layer) -> SyncReport:
        blender_scene = blender_scene or depsgraph.scene
        view_layer = view_layer or depsgraph.view_layer
        # the view layer's Material Override in every slot; set or cleared, every item's slots anew
        override = getattr(view_layer, "material_override", None)
        override_key = None if override is None else override.original.name_full
        full = self.scene is None or override_key != self._override_key or self._failed
        # only instances moved (placed_only.py): the last sync's items with their new matrices
        frame = (blender_scene.frame_current, blender_scene.frame_subframe)
        placing = self.place_from_updates and not full and not self._missed
        reported = (
            placing_from_updates(depsgraph, self._mover_index(), frame != self._frame, self._seen_moving)
            if placing
            else None
        )
        placed = None if reported is None else self._placed(reported, override, depsgraph.view_layer_eval)
        if placed is not None:
            assert reported is not None
            items, world, report, seen_moving, moved, table, shared = placed
            layout, by_data = self._layout, self._kept_meshes(items, reported.reshaped)
        else:
            dirty = Dirty(everything=True) if full else Dirty.from_updates(depsgraph)
            # materials read before and not changed since (after a failed sync, none is known unchanged)
            read = {} if self._table is None or self._failed else self._table.known
            table = MaterialTable({k: v for k, v in read.items() if k not in dirty.materials}, override)
            last = LastSync(self._items, self._by_data, self._world, self._seen_moving)
            items, world, by_data, report, seen_moving = walk(
                depsgraph, view_layer, self.scope, dirty, table, last, self.instancing
            )
            report.full = full
            animated = AnimatedMemo()
            layout = plan(items, world, self.instancing, lambda key: key in seen_moving or animated(items[key].origin))
            shared = shared_meshes(items, layout, self._shared)
            moved = [key for key, item in items.items() if item.moved]
        assert layout is not None
        # the last MoverIndex holds where only instances moved, or a walk found the same items
        index_holds = placed is not None or MoverIndex.still_holds(self._items, self._layout, items, layout)
        arrays = self._arrays(items, world, layout, shared, table, report, moved, None if placed is None else reported)
        report.materials_read = table.reads
        scene = self._make_scene(arrays, table, blender_scene, depsgraph, report, kept=placed is not None)
        # the sample only where the light's distance is to be measured (a pass over every item)
        points = primitive_sample(items, world, scene.spheres) if self.light_distance is None else np.zeros((0, 3))
        # where only instances moved, the light of the last sync (no light came or went)
        lamp = self._light_again(depsgraph, view_layer) if placed is not None else first_light(depsgraph, view_layer)
        found = None if lamp is None else gather_light(depsgraph, view_layer, points, self.light_distance, lamp)
        light = None
        if found is not None:
            light, self.light_distance = found
        if light is None:
            warnings.warn(
                f"scene '{blender_scene.name}' has no visible light; using a default point light near the camera",
                SubstituteWarning,
                stacklevel=2,
            )
            assert scene.camera is not None  # _make_scene always gives the scene a camera
            light = default_light(scene.camera)
        scene.light = light
        self.scene, self._table = scene, table
        self._items, self._by_data, self._layout, self._shared = items, by_data, layout, shared
        self._world, self._sphere_rows = world, arrays["sphere_rows"]
        self._seen_moving = seen_moving
        if not index_holds:
            self._index = None
        self._light = None if lamp is None else (lamp.original.name, lamp.original.name_full)
        self._moved = moved
        self._frame = frame
        self._missed = False
        self._override_key = override_key
        self.totals.add(report)
        return report

    def missed(self) -> None:
        """Say that an evaluation of the depsgraph was not synced (a caller that syncs only some
        of them: the sidebar's follow skips a hidden object or a new selection): the next sync
        walks the depsgraph, since the updates it is given do not name what changed before."""
        self._missed = True

    def _light_again(self, depsgraph, view_layer):
        """The last sync's light object, evaluated, looked up by its name (first_light where the
        name now names another object); None where that sync had none."""
        if self._light is None:
            return None
        name, full = self._light
        lamp = depsgraph.objects.get(name)
        if lamp is None or lamp.original.name_full != full:
            return first_light(depsgraph, view_layer)
        return lamp

    def _mover_index(self) -> MoverIndex:
        if self._index is None:
            assert self._layout is not None  # a sync ran
            self._index = MoverIndex.of(self._items, self._layout.mesh_of)
        return self._index

    def _placed(self, placing: Placing, override, layer_eval) -> tuple | None:
        """(items, world, report, seen moving, moved keys, material table, shared meshes) of the
        last sync with the matrices and meshes of `placing` (placed_only.place_moved,
        place_reshaped; `layer_eval`: the depsgraph's evaluated view layer, which the reshaped
        objects' flags are read in); None where the walk must run after all."""
        assert self.scene is not None and self._layout is not None
        placed = place_moved(self._items, self._world, self._moved, self._seen_moving, placing.moved, self.instancing)
        if placed is None:
            return None
        spheres = place_spheres(placed, self._sphere_rows, self._layout.mesh_of)
        if spheres is None:
            return None
        placing.spheres = spheres
        assert self._table is not None
        table = MaterialTable.kept(self._table, override)
        if not placing.reshaped:
            return (*placed, table, self._shared)
        shared = place_reshaped(
            placed, self._layout, self._shared, placing.reshaped, table, layer_eval, self.instancing
        )
        return None if shared is None else (*placed, table, shared)

    def _kept_meshes(self, items: dict, reshaped: dict) -> dict:
        """The last sync's meshes by data address, each reshaped item's under its new address only
        (changed in place, not copied: 1.6 ms a sync at 20,000 meshes; a sync that fails after
        this reads everything at the next, which makes the dict anew)."""
        by_data = self._by_data
        for key in reshaped:  # a reshaped item is a mesh (placed_only.MoverIndex: an instance)
            by_data.pop(self._items[key].data or 0, None)
        by_data.update((items[key].data, items[key].mesh) for key in reshaped)
        return by_data

    def _arrays(
        self,
        items: dict,
        world: np.ndarray,
        layout: Layout,
        shared: list[SharedMesh],
        table: MaterialTable,
        report,
        moved: list,
        placing: Placing | None = None,
    ) -> dict:
        """Mesh 0 (the items placed in the world: triangles, spheres and their material indices, in
        walk order; the material table is rebuilt in that order every sync), the shared meshes and
        the instances; the previous arrays where nothing changed. `moved`: the keys of the items
        that moved; `placing`: the items are the last sync's in its order and layout and only the
        instances (and spheres) `placing` names moved or were reshaped (placed_only.py): mesh 0 is
        the last sync's but the moved spheres' rows, and the instances' transforms but theirs."""
        previous = self.scene
        kept = placing is not None
        triangles: list = []
        spheres: list = []
        sphere_rows = self._sphere_rows  # a placed sync's spheres keep their rows (place_spheres)
        if kept:  # mesh 0's arrays are the last sync's, as they are (not concatenated again)
            assert previous is not None
            materials0 = (previous.tri_material, previous.sphere_material)
            empty = not len(previous.triangles) and not len(previous.spheres) and not shared
        else:
            tri_material, triangles, spheres, sphere_material, sphere_rows = mesh_zero(items, layout)
            materials0 = (
                np.concatenate(tri_material) if tri_material else np.zeros(0, np.int32),
                np.array(sphere_material, np.int32),
            )
            empty = not triangles and not spheres and not shared
        if empty:
            if not self.allow_empty:
                raise ExportError(nothing_in_scope(self.scope))
            warnings.warn(
                f"{nothing_in_scope(self.scope)}: the world alone is rendered", EmptySceneWarning, stacklevel=3
            )
        same_order = kept or list(self._items) == list(items)
        same_layout = kept or layout.same_as(self._layout)
        report.instances_moved = sum(1 for key in moved if layout.mesh_of[key])
        report.geometry = bool(previous is None or report.objects_read or moved or not same_order or not same_layout)
        report.refittable = (
            report.geometry
            and same_order
            and same_layout
            and (
                all(self._items[key].shape == items[key].shape for key in placing.reshaped)
                if placing is not None
                else [p.shape for p in self._items.values()] == [p.shape for p in items.values()]
            )
        )
        report.placeable = (
            report.geometry
            and previous is not None
            and same_order
            and same_layout
            and report.objects_read == 0
            and report.instances_moved == len(moved)
            and all(a is b for a, b in zip(shared, self._shared))
        )
        arrays: dict = {
            "sphere_rows": sphere_rows,
            "tri_material": materials0[0],
            "sphere_material": materials0[1],
            "meshes": [m.triangles for m in shared],
            "mesh_tri_material": [m.tri_material for m in shared],
        }
        if previous is not None and (kept or not report.geometry or report.placeable):
            arrays["triangles"], arrays["spheres"] = previous.triangles, previous.spheres
            if placing is not None and placing.spheres:  # spheres moved (placed_only.place_spheres)
                arrays["spheres"] = previous.spheres.copy()
                for row, sphere in placing.spheres.items():
                    arrays["spheres"][row] = sphere
        else:
            arrays["triangles"] = np.concatenate(triangles) if triangles else np.zeros((0, 3, 3), np.float32)
            arrays["spheres"] = np.array(spheres, np.float32).reshape(-1, 4)
        arrays["instance_mesh"], arrays["instance_transforms"] = instances(
            previous, world, layout, shared, arrays, report, None if placing is None else placing.rows()
        )
        report.materials = previous is None or not (
            previous.materials == table.materials
            and np.array_equal(previous.tri_material, arrays["tri_material"])
            and np.array_equal(previous.sphere_material, arrays["sphere_material"])
            and len(previous.mesh_tri_material) == len(shared)
            and all(np.array_equal(a, b) for a, b in zip(previous.mesh_tri_material, arrays["mesh_tri_material"]))
        )
        return arrays

    def _make_scene(
        self, arrays: dict, table: MaterialTable, blender_scene, depsgraph, report, kept: bool = False
    ) -> Scene:
        """The sync's Scene: a copy of the last one where nothing but the camera and sky changed
        (the same arrays: renderers keep what they uploaded), or where only instances or spheres
        moved or instances changed their meshes (`kept`, placed_only.py: mesh 0's triangles and
        the materials the last sync's, the instances and spheres set again), else a new one.
        Fields are checked as they are set (scene.py), so a copy checks only what changed (mesh
        0's 240,000 triangles took 3.4 ms a placed sync, and grow with the static scene)."""
        camera = self._camera(blender_scene, depsgraph)
        sky = gather_sky(blender_scene, depsgraph)
        previous = self.scene
        if previous is not None and (kept or not (report.geometry or report.materials)):
            scene = copy.copy(previous)
            if kept:
                for name in ("meshes", "mesh_tri_material"):
                    if any(a is not b for a, b in zip(arrays[name], getattr(previous, name), strict=True)):
                        setattr(scene, name, arrays[name])
                for name in ("spheres", "instance_mesh", "instance_transforms"):
                    if arrays[name] is not getattr(previous, name):
                        setattr(scene, name, arrays[name])
            scene.camera = camera if camera is not None else default_camera(scene.world_bounds())
            r, g, b = (float(c) for c in sky)
            scene.sky = (r, g, b)
            return scene
        scene = Scene(
            triangles=arrays["triangles"],
            spheres=arrays["spheres"],
            materials=table.materials,
            tri_material=arrays["tri_material"],
            sphere_material=arrays["sphere_material"],
            camera=camera,
            sky=sky,
            meshes=arrays["meshes"],
            mesh_tri_material=arrays["mesh_tri_material"],
            instance_mesh=arrays["instance_mesh"],
            instance_transforms=arrays["instance_transforms"],
        )
        if scene.camera is None:  # nothing to frame (allow_empty): the fallback camera
            scene.camera = default_camera(None)
        return scene

    def _camera(self, blender_scene, depsgraph):
        try:
            return gather_camera(blender_scene, depsgraph, camera=self.camera_object, size=self.frame_size)
        except ExportError as error:
            if self.require_camera:
                raise
            warnings.warn(f"{error}; using a default camera that frames the geometry", SubstituteWarning, stacklevel=3)
            return None
