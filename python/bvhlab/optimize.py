"""Optimisation of a built tree by reinsertion (issue 36; Bittner, Hapala and Havran 2013; C++
core_cpp/include/bvhlab/optimize.h): `OptimizeConfig` says how long, `OptimizeStats` what it did."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

from . import _checks, _core

#: The core's defaults: one definition, in optimize.h.
_CORE_DEFAULTS = _core.OptimizeConfig()


@dataclass(frozen=True)
class OptimizeConfig:
    """How `Bvh.optimize` restructures a tree: in batches (at most `iterations`; it stops earlier
    once a batch gains nothing), each taking out the worst `batch_fraction` of the inner nodes by
    Bittner et al.'s inefficiency and putting their children back where the SAH finds them
    cheapest; `time_budget_ms` (0: none) stops it between reinsertions, keeping what it did (the
    tree then depends on the machine's speed; the iteration bound does not). With `merge_leaves`,
    subtrees of at most the tree's max_leaf_size primitives that are cheaper as one leaf become one.

    Defaults are the core's; values are checked by it (ValueError) when the config is made."""

    iterations: int = _CORE_DEFAULTS.iterations
    time_budget_ms: float = _CORE_DEFAULTS.time_budget_ms
    batch_fraction: float = _CORE_DEFAULTS.batch_fraction
    merge_leaves: bool = _CORE_DEFAULTS.merge_leaves

    def __post_init__(self):
        self.core()

    def core(self) -> _core.OptimizeConfig:
        c = _core.OptimizeConfig()
        c.iterations = _checks.integer("iterations", self.iterations, 0, 2**32 - 1)
        c.time_budget_ms = _checks.setting("time_budget_ms", self.time_budget_ms)
        c.batch_fraction = _checks.setting("batch_fraction", self.batch_fraction)
        c.merge_leaves = _checks.flag("merge_leaves", self.merge_leaves)
        c.validate()
        return c

    def replace(self, **changes) -> OptimizeConfig:
        return dataclasses.replace(self, **changes)


@dataclass(frozen=True)
class OptimizeStats:
    """What one optimisation did: the SAH cost before and after (sah_after <= sah_before), the
    batches run, the nodes taken out and of them the reinsertions kept, the subtrees merged into
    leaves, its wall time and why it stopped ("converged", "iterations" or "time_budget")."""

    sah_before: float
    sah_after: float
    iterations: int
    attempts: int
    reinsertions: int
    leaves_merged: int
    ms: float
    stop: str
