"""Which evaluated objects an export covers: the selected ones or every visible one, instances
(collection instances, instancing by vertices or geometry nodes) included."""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any, NamedTuple

import numpy as np

from .errors import ExportError

SCOPES = ("selected", "visible")


class InScope(NamedTuple):
    """One object or instance an export covers. `key` names it across depsgraph evaluations:
    (owner's name, object's name, persistent id of the instance or ()). `owner`: the original
    object itself, or the original object that instances it; `source`: the original object shown
    (the owner itself for an object). Originals stay valid after the iterator moves on."""

    obj: Any  # a bpy.types.Object (bpy has no type stubs)
    matrix: np.ndarray
    name: str
    key: tuple
    owner: Any = None
    source: Any = None


def objects_in_scope(depsgraph, view_layer, scope: str) -> Iterator[tuple[object, np.ndarray, str]]:
    """Yield (evaluated object, 4×4 float64 world matrix, name for messages) for every object and
    instance the depsgraph shows whose owner (the object itself, or the object that instances it)
    is in `scope`. An instance's data is only valid until the next item: use it before moving on."""
    for item in instances_in_scope(depsgraph, view_layer, scope):
        yield item.obj, item.matrix, item.name


def instances_in_scope(depsgraph, view_layer, scope: str) -> Iterator[InScope]:
    """`objects_in_scope`, with a key for each item (see InScope)."""
    if scope not in SCOPES:
        raise ExportError(f"unknown scope '{scope}'; expected one of: {', '.join(SCOPES)}")
    in_scope = _selected if scope == "selected" else _visible
    decided: dict[str, bool] = {}  # instancers own thousands of instances: ask Blender once each
    for instance in depsgraph.object_instances:
        owner = (instance.parent if instance.is_instance else instance.object).original
        owner_name = owner.name_full
        if owner_name not in decided:
            decided[owner_name] = in_scope(owner, view_layer)
        if decided[owner_name]:
            obj = instance.object
            if instance.is_instance:
                source = obj.original
                name, key = (
                    f"{obj.name} (instanced by {owner.name})",
                    (owner_name, source.name_full, tuple(instance.persistent_id)),
                )
            else:
                source, name, key = owner, obj.name, (owner_name, owner_name, ())
            yield InScope(obj, _matrix(instance.matrix_world), name, key, owner, source)


def _matrix(m) -> np.ndarray:
    """A mathutils 4×4 Matrix as float64 (4,4), rows unpacked (several times faster than np.array(m),
    which goes through the sequence protocol element by element: it counts for 10,000 instances).
    A copy first: the depsgraph's matrix wraps Blender's memory and reads it again for every row
    and element asked (a third faster for 10,000 instances)."""
    m = m.copy()
    return np.array([*m[0], *m[1], *m[2], *m[3]], np.float64).reshape(4, 4)


def _selected(obj, view_layer) -> bool:
    return obj.select_get(view_layer=view_layer)


def _visible(obj, view_layer) -> bool:
    return obj.visible_get(view_layer=view_layer)
