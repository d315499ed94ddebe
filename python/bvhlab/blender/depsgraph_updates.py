"""What `depsgraph.updates` reports as changed since the last evaluation, by name: the objects and
meshes whose geometry changed and the materials (LiveScene.sync reads only these again)."""

from __future__ import annotations

from dataclasses import dataclass, field

import bpy


@dataclass
class Dirty:
    """Names (original, full) of what depsgraph.updates reports; `everything` on the first sync."""

    everything: bool = False
    objects: set = field(default_factory=set)
    meshes: set = field(default_factory=set)
    materials: set = field(default_factory=set)

    @classmethod
    def from_updates(cls, depsgraph) -> Dirty:
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
