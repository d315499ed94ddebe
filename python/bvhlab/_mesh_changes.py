"""Changes of a tree that an InstancedBvh places (a mesh changed through `InstancedBvh.meshes[k]`:
`Bvh.refit`, `update`, `optimize`): checked against every live InstancedBvh placing it, and undone
where one of its instances would leave the coordinate range. Before, the change stayed, and every
later read of the InstancedBvh raised, `meshes` too, so it could not be changed back (a helper's
audit)."""

from __future__ import annotations

import contextlib
import threading
from collections.abc import Callable, Iterable
from typing import TYPE_CHECKING, TypeVar

if TYPE_CHECKING:
    from .bvh import Bvh
    from .instanced import InstancedBvh

T = TypeVar("T")

#: Guards every tree's `_placed_by` (a WeakSet: iterated while another thread added to it, it
#: raised "Set changed size during iteration": the review). Held for no other lock.
_PLACED = threading.Lock()


def placing(owner: InstancedBvh, meshes: Iterable[Bvh]) -> None:
    """Tells each of `meshes` that `owner` places it."""
    with _PLACED:
        for m in meshes:
            m._placed_by.add(owner)


def checked_change(tree: Bvh, change: Callable[[], T]) -> T:
    """Runs `change` (a refit, update or optimisation of `tree`) and returns what it returns. Where
    InstancedBvhs place `tree`, their instances of it are checked with the new version as their
    next TLAS will be (not made now: a caller changing several meshes makes one); where one is
    refused, or anything is raised after the change, the version before it is published again (as
    a new revision: no cache keyed by revision takes the undone one for it) and the error raised.
    The check is against the instances as placed now: to move a mesh and its instances together
    near the range's edge, `place` first. The tree's own lock, then each owner's (by id: one order
    everywhere), are held throughout: a `place` meanwhile checked nothing of this change, and an
    undo put back the version before its own change over another thread's change (the review)."""
    with _PLACED:
        owners = sorted((o for o in tree._placed_by if o._places(tree)), key=id)
    if not owners:
        return change()
    with tree._changing, contextlib.ExitStack() as held:  # a Ctrl-C between two takes leaves none held
        for owner in owners:
            held.enter_context(owner._lock)
        before = tree._core.fork()
        result = change()
        try:
            for owner in owners:
                owner._check_placement(tree)
        except BaseException as e:
            tree._core.restore(before)
            if isinstance(e, ValueError):
                raise ValueError(f"change refused, the tree kept as it was (an InstancedBvh places it): {e}") from None
            raise
        return result
