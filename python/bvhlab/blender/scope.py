"""Which evaluated objects an export covers: the selected ones or every visible one, instances
(collection instances, instancing by vertices or geometry nodes) included."""
from __future__ import annotations

from typing import Iterator

import numpy as np

from .errors import ExportError

SCOPES = ("selected", "visible")


def objects_in_scope(depsgraph, view_layer, scope: str) -> Iterator[tuple[object, np.ndarray, str]]:
    """Yield (evaluated object, 4×4 float64 world matrix, name for messages) for every object and
    instance the depsgraph shows whose owner (the object itself, or the object that instances it)
    is in `scope`. An instance's data is only valid until the next item: use it before moving on."""
    if scope not in SCOPES:
        raise ExportError(f"unknown scope '{scope}'; expected one of: {', '.join(SCOPES)}")
    in_scope = _selected if scope == "selected" else _visible
    decided: dict[str, bool] = {}  # instancers own thousands of instances: ask Blender once each
    for instance in depsgraph.object_instances:
        owner = (instance.parent if instance.is_instance else instance.object).original
        key = owner.name_full
        if key not in decided:
            decided[key] = in_scope(owner, view_layer)
        if decided[key]:
            obj = instance.object
            name = f"{obj.name} (instanced by {owner.name})" if instance.is_instance else obj.name
            yield obj, np.array(instance.matrix_world, np.float64), name


def _selected(obj, view_layer) -> bool:
    return obj.select_get(view_layer=view_layer)


def _visible(obj, view_layer) -> bool:
    return obj.visible_get(view_layer=view_layer)
