"""Which evaluated objects an export covers: the selected ones or every visible one, instances
(collection instances, instancing by vertices or geometry nodes) included.

Read for 10,000 instances and more (issue 34), so each item costs as few of Blender's attribute
reads as it can: the object's type first (instancers, cameras and lights are passed over before
anything else is read), the owner decided once per instancer, the name for messages made from
the key only when a message needs it, and the world matrix kept as a `mathutils.Matrix` copy that
`matrices_array` turns into numpy for all items at once."""

from __future__ import annotations

from collections.abc import Iterator
from itertools import chain
from typing import Any, NamedTuple

import numpy as np

from .errors import ExportError

SCOPES = ("selected", "visible")


class InScope(NamedTuple):
    """One object or instance an export covers. `key` names it across depsgraph evaluations:
    (owner's full name, shown object's full name, persistent id of the instance or ()). `matrix`:
    its world matrix, a `mathutils.Matrix` copy (`matrices_array`). `owner`: the original object
    itself, or the original object that instances it; `source`: the original object shown (the
    owner itself for an object). Originals stay valid after the iterator moves on; `obj` does not.
    `holder`: the owner as evaluated (`obj` itself for an object, the evaluated instancer): what
    the frame's flags are read from (a render's depsgraph never writes its animation back to the
    originals: keyframed Ray Visibility and Holdout stayed at the UI frame's in renders)."""

    obj: Any  # a bpy.types.Object (bpy has no type stubs)
    type: str  # obj.type, read once
    matrix: Any  # a mathutils.Matrix
    key: tuple
    owner: Any = None
    source: Any = None
    holder: Any = None

    @property
    def name(self) -> str:
        return item_name(self.key)


def item_name(key: tuple) -> str:
    """An item's name for messages, from its key (InScope.key)."""
    owner, shown, persistent_id = key
    return f"{shown} (instanced by {owner})" if persistent_id else shown


def instances_in_scope(depsgraph, view_layer, scope: str, types=None) -> Iterator[InScope]:
    """Every object and instance the depsgraph shows whose owner (the object itself, or the object
    that instances it) is in `scope`, of the object `types` given (None: all); not an instancer's
    own geometry where the depsgraph does not show it (`show_self`). An instance's `obj`
    is only valid until the next item: use it before moving on."""
    if scope not in SCOPES:
        raise ExportError(f"unknown scope '{scope}'; expected one of: {', '.join(SCOPES)}")
    in_scope = _selected if scope == "selected" else visibility(depsgraph)
    # Blender's structs hash and compare by the address they wrap, so the evaluated owner and the
    # original shown are dict keys without a call to as_pointer (a method call: slower than the
    # reads it saves). An instancer owns thousands of instances: its original, name and scope are
    # asked once; an object shown by thousands of instances has its name read once.
    owners: dict[Any, tuple] = {}
    names: dict[Any, str] = {}
    copies: dict[Any, bool] = {}  # shown_object's answers
    for instance in depsgraph.object_instances:
        is_instance = instance.is_instance
        obj = shown_object(instance, copies) if is_instance else instance.object
        kind = obj.type
        if types is not None and kind not in types:
            continue
        # an instancer whose own geometry is not shown (a particle emitter with Show Emitter off
        # for the depsgraph's mode, render or viewport; one inside an instanced collection too), as
        # Cycles skips it; its instances stay
        if not instance.show_self:
            continue
        holder = instance.parent if is_instance else obj
        known = owners.get(holder)
        if known is None:
            original = holder.original
            known = owners[holder] = (original, original.name_full, in_scope(original, view_layer))
        owner, owner_name, shown = known
        if not shown:
            continue
        if is_instance:
            source = obj.original
            name = names.get(source)
            if name is None:
                name = names[source] = source.name_full
            key = (owner_name, name, instance.persistent_id[:])
        else:
            source, key = owner, (owner_name, owner_name, ())
        # a copy: the depsgraph's matrix wraps Blender's memory of this instance only
        yield InScope(obj, kind, instance.matrix_world.copy(), key, owner, source, holder)


#: Object types whose instances are copies of the object instanced (shown_object): types that
#: carry no geometry-nodes output of their own, and meshes without a geometry-nodes modifier. A
#: curve, text, surface or metaball object shows its surface as an instance of type MESH whose data
#: is not the object's (walk.py GEOMETRY_TYPES), and so does a point cloud, curves or volume object.
_COPIED_TYPES = frozenset({"MESH", "EMPTY", "LIGHT", "CAMERA", "LIGHT_PROBE", "SPEAKER", "ARMATURE", "LATTICE"})


def shown_object(instance, copies: dict):
    """The evaluated object a depsgraph instance (`is_instance`) shows, read without
    `instance.object` where the instance is a copy of `instance.instance_object`. Each read of
    `DepsgraphObjectInstance.object` for an instance leaks Blender's Python wrapper of its
    temporary object (measured: 62 bytes a read in bpy 4.2, 124 in 4.5 and 5.0; 100,000
    geometry-nodes instances, 6-12 MB each walk, every sync of an animation; `instance_object` and
    `parent` leak nothing). An instance of an object (a collection's, a particle's, a vertex's or
    face's, geometry nodes' "As Instance") is that object with the instance's matrix: the same type,
    data, material slots and original, which is all an export reads of it (the matrix is the
    instance's own, `instance.matrix_world`). Geometry that geometry nodes instance (a component of
    a geometry set: "As Instance" off) is shown by a copy of the instancer with other data and type,
    which only `instance.object` has: read so where the instanced object could be such an
    instancer (a geometry-nodes modifier, or a type outside _COPIED_TYPES). `copies` keeps the
    answer per instanced object for the walk (10,000 instances of one object: one look)."""
    source = instance.instance_object
    if source is None:
        return instance.object
    copied = copies.get(source)
    if copied is None:
        copied = copies[source] = source.type in _COPIED_TYPES and not any(
            modifier.type == "NODES" for modifier in source.modifiers
        )
    return source if copied else instance.object


def matrices_array(matrices: list) -> np.ndarray:
    """`mathutils.Matrix` 4×4s → float64 (N,4,4), all at once: each row sliced into a tuple in one
    call, the floats gathered by np.fromiter (np.array(m) reads a Matrix element by element through
    the sequence protocol: 60× slower; unpacking rows 3×)."""
    rows = chain.from_iterable(row[:] for m in matrices for row in m)
    return np.fromiter(rows, np.float64, 16 * len(matrices)).reshape(-1, 4, 4)


def _selected(obj, view_layer) -> bool:
    return obj.select_get(view_layer=view_layer)


def visibility(depsgraph):
    """Whether an original object is visible to an export from `depsgraph`, as (object, view
    layer) -> bool. A final render's depsgraph holds only what renders (Blender leaves out what is
    disabled in renders, and collections excluded from them), so all of it is visible, also what
    the viewport hides (the eye, Disable in Viewports), as Cycles renders it; a viewport's
    depsgraph, what the viewport shows."""
    return _rendered if depsgraph.mode == "RENDER" else _visible


def _rendered(obj, view_layer) -> bool:
    return True


def _visible(obj, view_layer) -> bool:
    return obj.visible_get(view_layer=view_layer)


def nothing_in_scope(scope: str) -> str:
    """The error (or, where allowed, the warning) of an export with no mesh in `scope`."""
    if scope == "selected":
        return (
            "no mesh in scope: no selected object has faces or spheres (select meshes, or use scope 'visible'; "
            "loose edges and vertices are not rendered)"
        )
    return (
        "no mesh in scope: no visible object has faces or spheres (add a mesh or unhide one; loose edges and "
        "vertices are not rendered)"
    )
