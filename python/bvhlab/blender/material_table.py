"""One `bvhlab.Material` per Blender material used, and the slot → table index of each object."""

from __future__ import annotations

import numpy as np

from ..scene import Material
from .material import gather_material


class MaterialTable:
    """Collects materials in first-use order; every Blender material is read once. `known` (name →
    Material) holds materials read before and still valid: they are taken from it instead of read
    again, and every material read is added to it (`reads` counts them)."""

    def __init__(self, known: dict[str, Material] | None = None):
        self.materials: list[Material] = []
        self.known = {} if known is None else known
        self.reads = 0
        self._index: dict[str, int] = {}  # original material's full name ('' for an empty slot)

    def index_of(self, material) -> int:
        """Table index of a Blender material (evaluated or original; None = empty slot)."""
        key = "" if material is None else material.original.name_full
        if key not in self._index:
            if key not in self.known:
                self.known[key] = gather_material(material)
                self.reads += 1
            self._index[key] = len(self.materials)
            self.materials.append(self.known[key])
        return self._index[key]

    def slot_indices(self, obj) -> np.ndarray:
        """int32 table index of each material slot of an evaluated object (one entry if it has none)."""
        slots = [slot.material for slot in obj.material_slots] or [None]
        return np.array([self.index_of(m) for m in slots], np.int32)


def map_slots(slot_table: np.ndarray, slots: np.ndarray) -> np.ndarray:
    """Per-triangle slot numbers → table indices (`slot_table`: MaterialTable.slot_indices of the
    object); numbers past the last slot use the last one, as Blender does."""
    return slot_table[np.clip(slots, 0, len(slot_table) - 1)]
