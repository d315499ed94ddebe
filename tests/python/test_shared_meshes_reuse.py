"""instancing.shared_meshes reuses the last sync's SharedMesh of each mesh read again unchanged
(its arrays, so its tree is kept) by looking it up, not by searching the last sync's list for each
mesh: a walked sync of 10,000 movers (each an animated object with a mesh of its own) spent 14 s
in that search."""

import numpy as np

from bvhlab.blender.instancing import Item, Layout, shared_meshes


class _Mesh:
    slots = np.zeros(2, np.int32)
    triangles = np.zeros((2, 3, 3), np.float32)


class _Counted(list):
    """A list that counts the entries its iterators hand out."""

    handed = 0

    def __iter__(self):
        for entry in super().__iter__():
            _Counted.handed += 1
            yield entry


def _scene(n: int):
    meshes = [_Mesh() for _ in range(n)]
    items = {
        (f"M{i}", f"M{i}", ()): Item(m, None, np.eye(4), i, np.array([0], np.int32), (f"M{i}", f"M{i}", ()))
        for i, m in enumerate(meshes)
    }
    layout = Layout(mesh_of={key: i + 1 for i, key in enumerate(items)}, groups=[(i, b"") for i in range(n)])
    return items, layout


def test_each_mesh_kept_is_found_without_a_search_of_the_last_sync():
    items, layout = _scene(3000)
    first = shared_meshes(items, layout, [])
    _Counted.handed = 0
    again = shared_meshes(items, layout, _Counted(first))
    assert all(a is b for a, b in zip(again, first)), "an unchanged mesh lost its arrays"
    assert _Counted.handed <= 2 * len(first), f"{_Counted.handed:,} entries looked at for {len(first):,} meshes"


def test_a_mesh_with_other_materials_is_not_reused():
    items, layout = _scene(3)
    first = shared_meshes(items, layout, [])
    key = next(iter(items))
    items[key].slot_table = np.array([1], np.int32)
    again = shared_meshes(items, layout, first)
    assert again[0] is not first[0] and list(again[0].tri_material) == [1, 1]
    assert again[1] is first[1] and again[2] is first[2]
