"""What one sync of a LiveScene found (`SyncReport`), and the counts over its life (`SyncTotals`)."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass
class SyncReport:
    """What one sync found. `geometry`: the triangles, spheres or instances differ from the last
    sync; `refittable`: they differ only in position (same primitives, same order, same instances
    of the same meshes: a refit of the flattened scene can follow); `placeable`: only instance
    transforms differ (every mesh's arrays are the last sync's: only the TLAS is built again);
    `materials`: the material table or the primitives' materials differ. `objects_read` counts
    meshes read (a mesh shared by instances once), `objects_moved` items placed again without a
    read, `instances_moved` those of them that are instances of a shared mesh (a new transform).
    `placed_only`: the depsgraph was not walked, the updates said that only instances (or the
    camera or light) moved (placed_only.py)."""

    full: bool = False
    placed_only: bool = False
    objects_read: int = 0
    objects_moved: int = 0
    instances_moved: int = 0
    materials_read: int = 0
    geometry: bool = False
    refittable: bool = False
    placeable: bool = False
    materials: bool = False


@dataclass
class SyncTotals:
    """Counts over a LiveScene's life (tests count exports with them)."""

    syncs: int = 0
    full_syncs: int = 0
    objects_read: int = 0
    objects_moved: int = 0
    instances_moved: int = 0
    materials_read: int = 0

    def add(self, report: SyncReport) -> None:
        self.syncs += 1
        self.full_syncs += report.full
        self.objects_read += report.objects_read
        self.objects_moved += report.objects_moved
        self.instances_moved += report.instances_moved
        self.materials_read += report.materials_read
