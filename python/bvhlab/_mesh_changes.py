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
    from . import _core
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


def checked_change(tree: Bvh, change: Callable[[_core.Bvh], T]) -> T:
    """Runs `change` (a refit, update or optimisation, given the core tree to change) on `tree` and
    returns what it returns. Where InstancedBvhs place `tree`, the change is made on a fork (the
    tree's version shared, not copied), their instances of it are checked with the fork as their
    next TLAS will be (not made now: a caller changing several meshes makes one), and only a change
    they all accept is published, as one new revision (a copy of the fork's version); a refused one
    (ValueError), or anything raised meanwhile, leaves the tree and its revision as they were.
    Published first and undone after the check, a refused version was seen by the tree's readers
    in half of their reads while another thread's refits were refused, and each refusal cost two
    revisions (an audit). The check is against the instances as placed now: to move a mesh and its
    instances together near the range's edge, `place` first. The tree's own lock, then each
    owner's (by id: one order everywhere), are held throughout: a `place` meanwhile checked nothing
    of this change, and a publication put another thread's change aside (the review)."""
    with _PLACED:
        owners = sorted((o for o in tree._placed_by if o._places(tree)), key=id)
    if not owners:
        return change(tree._core)
    with tree._changing, contextlib.ExitStack() as held:  # a Ctrl-C between two takes leaves none held
        for owner in owners:
            held.enter_context(owner._lock)
        work = tree._core.fork()
        result = change(work)
        try:
            for owner in owners:
                owner._check_placement(tree, work)
        except ValueError as e:
            raise ValueError(f"change refused, the tree kept as it was (an InstancedBvh places it): {e}") from None
        tree._core.restore(work)
        return result
