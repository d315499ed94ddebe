"""Updates of a tree over deforming geometry (issue 34; C++ core_cpp/include/bvhlab/update.h):
`UpdateConfig` says how (rebuild, refit, partial, adaptive), `UpdateStats` what ran."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

from . import _checks, _core

#: Policy names as the core spells them, and its defaults: one definition, in update.h.
UPDATE_POLICIES = tuple(_core.UPDATE_POLICIES)
_CORE_DEFAULTS = _core.UpdateConfig()


@dataclass(frozen=True)
class UpdateConfig:
    """How `Bvh.update` updates a tree for moved geometry (same primitive counts):

    - "rebuild": a fresh build with the tree's settings;
    - "refit": boxes only; the topology stays and its SAH cost may grow;
    - "partial": refit, then rebuild each topmost subtree (of at least `min_subtree_primitives`)
      whose SAH cost grew past `subtree_growth` × its cost when built (selective restructuring,
      Yoon et al. 2007);
    - "adaptive": refit; once the tree's cost passes `target_growth` × its cost when built,
      rebuild the subtrees that hold most of the grown cost per primitive (Yoon et al. 2007
      restructure only where culling efficiency dropped), at most `restructure_share` of the
      primitives an update, then (past `top_growth`) the levels above the subtrees of at most
      `top_cut_primitives` over their boxes; the whole tree when its cost is still past `tree_growth` × its reference
      (its cost when built, taken as keeping its area-weighted cost where the root's box has grown since: a fresh
      build's cost falls where the geometry spreads).

    Defaults are the core's; values are checked by it (ValueError) when the config is made."""

    policy: str = _CORE_DEFAULTS.policy
    subtree_growth: float = _CORE_DEFAULTS.subtree_growth
    target_growth: float = _CORE_DEFAULTS.target_growth
    restructure_share: float = _CORE_DEFAULTS.restructure_share
    tree_growth: float = _CORE_DEFAULTS.tree_growth
    min_subtree_primitives: int = _CORE_DEFAULTS.min_subtree_primitives
    #: adaptive: after the subtrees, the levels above subtrees of at most this many primitives are
    #: rebuilt over their boxes (0: never)
    top_cut_primitives: int = _CORE_DEFAULTS.top_cut_primitives
    #: adaptive: that step runs only while the tree, after its subtrees, costs more than this ×
    #: its cost when built
    top_growth: float = _CORE_DEFAULTS.top_growth
    #: adaptive: the top's cut also takes whole a subtree of at most this many primitives that is as
    #: built (just rebuilt, or its cost unchanged: moved as one); 0: never
    top_intact_primitives: int = _CORE_DEFAULTS.top_intact_primitives
    #: adaptive: where the top's first cut is dense (over 0.1 boxes a primitive), it is taken again
    #: with subtrees of at most this many primitives (the intact ones whole); the cut of
    #: top_cut_primitives where that top would pass tree_growth; 0: never
    top_coarse_cut_primitives: int = _CORE_DEFAULTS.top_coarse_cut_primitives
    #: also build a fresh tree, only to report its SAH cost (UpdateStats.fresh_sah_cost): a build's time
    measure_fresh: bool = _CORE_DEFAULTS.measure_fresh

    def __post_init__(self):
        self.core()

    def core(self) -> _core.UpdateConfig:
        c = _core.UpdateConfig()
        c.policy = _checks.choice("policy", self.policy, UPDATE_POLICIES)
        c.subtree_growth = _checks.setting("subtree_growth", self.subtree_growth, lo=1)
        c.tree_growth = _checks.setting("tree_growth", self.tree_growth, lo=1)
        c.target_growth = _checks.setting("target_growth", self.target_growth, lo=1)
        c.restructure_share = _checks.setting("restructure_share", self.restructure_share, 0, 1, zero_ok=False)
        c.min_subtree_primitives = _checks.integer("min_subtree_primitives", self.min_subtree_primitives, 0, 2**32 - 1)
        c.top_cut_primitives = _checks.integer("top_cut_primitives", self.top_cut_primitives, 0, 2**32 - 1)
        c.top_growth = _checks.setting("top_growth", self.top_growth, lo=1)
        c.top_intact_primitives = _checks.integer("top_intact_primitives", self.top_intact_primitives, 0, 2**32 - 1)
        c.top_coarse_cut_primitives = _checks.integer(
            "top_coarse_cut_primitives", self.top_coarse_cut_primitives, 0, 2**32 - 1
        )
        c.measure_fresh = _checks.flag("measure_fresh", self.measure_fresh)
        c.validate()
        return c

    def replace(self, **changes) -> UpdateConfig:
        return dataclasses.replace(self, **changes)


def update_config(config: UpdateConfig | None, changes: dict) -> UpdateConfig:
    """The UpdateConfig an update call asks for: `config` (None: the defaults) with `changes` (its
    fields by name) on top; TypeError or ValueError naming what is wrong."""
    if config is None:
        config = UpdateConfig()
    elif not isinstance(config, UpdateConfig):
        raise TypeError(f"config must be a bvhlab.UpdateConfig, got {type(config).__name__}")
    return config.replace(**changes) if changes else config


@dataclass(frozen=True)
class UpdateStats:
    """What one update did: the policy that ran (adaptive's choice), its wall time, the SAH cost
    of the updated tree, the subtrees and primitives rebuilt, and (with measure_fresh, else None)
    the SAH cost of a fresh build over the same geometry."""

    policy: str
    ms: float
    sah_cost: float
    subtrees_rebuilt: int
    primitives_rebuilt: int
    fresh_sah_cost: float | None = None
    #: adaptive: the subtrees whose boxes the levels above them were rebuilt over (0: not)
    top_boxes: int = 0
