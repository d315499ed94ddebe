"""`BuildConfig`, the one typed object a build is asked for, and the split methods, axis policies,
defaults and limits it is checked against (one definition, in the C++ core's build_config.h)."""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field, fields

import numpy as np

from . import _checks, _core

#: Split methods and axis policies as the C++ core names them (its table of methods), and the
#: defaults and limits of a build: one definition, in core_cpp/include/bvhlab/build_config.h.
METHODS = tuple(_core.SPLIT_METHODS)
#: The methods that divide nodes into `bins` buckets over `bin_bounds` (sah, sbvh): the only ones
#: those settings change, and whose stats report them (None for the rest).
BINNED_METHODS = tuple(_core.BINNED_METHODS)
AXES = tuple(_core.AXIS_POLICIES)
BIN_BOUNDS = tuple(_core.BIN_BOUNDS)
_CORE_DEFAULTS = _core.BuildConfig()
DEFAULT_METHOD: str = _CORE_DEFAULTS.method
DEFAULT_AXIS: str = _CORE_DEFAULTS.axis
DEFAULT_BINS: int = _CORE_DEFAULTS.bins
DEFAULT_BIN_BOUNDS: str = _CORE_DEFAULTS.bin_bounds
DEFAULT_MAX_LEAF_SIZE: int = _CORE_DEFAULTS.max_leaf_size
DEFAULT_SAH_BLOCK: int = _CORE_DEFAULTS.sah_block
MIN_BINS, MAX_BINS = int(_core.MIN_BINS), int(_core.MAX_BINS)
MAX_LEAF_SIZE = int(_core.MAX_LEAF_SIZE)
MAX_SAH_BLOCK = int(_core.MAX_SAH_BLOCK)


def _uint32(name: str, value, limits: tuple[int, int]) -> int:
    """An int for a uint32 field of the core's config: its type is checked here; its range by the
    core's validate (`limits` only word the message for a value no uint32 holds)."""
    value = _checks.integer(name, value, -math.inf, math.inf)  # the type; the range by `limits`
    if not 0 <= value < 2**32:
        raise ValueError(f"{name} must be between {limits[0]} and {limits[1]}, got {value}")
    return value


@dataclass(frozen=True)
class BuildConfig:
    """What a tree is built with: the one typed object a build is asked for, from the API, the CLI
    and the add-on alike. Defaults are the core's (build_config.h); values are checked once, by
    the core (ValueError naming the setting), when the config is made. Two configs are equal when
    they give the same tree (`threads` never changes it)."""

    method: str = DEFAULT_METHOD
    bins: int = DEFAULT_BINS
    bin_bounds: str = DEFAULT_BIN_BOUNDS
    axis: str = DEFAULT_AXIS
    max_leaf_size: int = DEFAULT_MAX_LEAF_SIZE
    sah_block: int = DEFAULT_SAH_BLOCK
    seed: int = _CORE_DEFAULTS.seed
    sbvh_alpha: float = _CORE_DEFAULTS.sbvh_alpha
    sbvh_budget: float = _CORE_DEFAULTS.sbvh_budget
    sbvh_unsplit: bool = _CORE_DEFAULTS.sbvh_unsplit
    threads: int = field(default=_CORE_DEFAULTS.threads, compare=False)

    def __post_init__(self):
        c = self.core()
        # each setting as the Python type of its field, so that equal settings written differently
        # (sbvh_alpha 1 and 1.0, bins 12 and numpy's 12) record and hash alike (stats files, sweep
        # keys); a float as the shortest decimal of the float32 the core holds: the default
        # sbvh_alpha, float32(3e-4), did not equal 3e-4 typed (a tree file saved with the default
        # was refused with it), and float32's own digits (9.999999747378752e-06 for 1e-5) would show
        # in tables and labels (review)
        for name in ("bins", "max_leaf_size", "sah_block", "seed", "threads"):
            object.__setattr__(self, name, int(getattr(c, name)))
        for name in ("sbvh_alpha", "sbvh_budget"):
            object.__setattr__(self, name, float(str(np.float32(getattr(self, name)))))
        object.__setattr__(self, "sbvh_unsplit", bool(self.sbvh_unsplit))

    def core(self) -> _core.BuildConfig:
        """The C++ BuildConfig (types checked here, values by the core's validate)."""
        c = _core.BuildConfig()
        c.method = _checks.choice("method", self.method, METHODS)
        c.axis = _checks.choice("axis", self.axis, AXES)
        c.bin_bounds = _checks.choice("bin_bounds", self.bin_bounds, BIN_BOUNDS)
        c.bins = _uint32("bins", self.bins, (MIN_BINS, MAX_BINS))
        c.max_leaf_size = _uint32("max_leaf_size", self.max_leaf_size, (1, MAX_LEAF_SIZE))
        c.sah_block = _uint32("sah_block", self.sah_block, (1, MAX_SAH_BLOCK))
        c.seed = _checks.integer("seed", self.seed, 0, 2**64 - 1)
        c.sbvh_alpha = _checks.setting("sbvh_alpha", self.sbvh_alpha)
        c.sbvh_budget = _checks.setting("sbvh_budget", self.sbvh_budget)
        c.sbvh_unsplit = _checks.flag("sbvh_unsplit", self.sbvh_unsplit)
        c.threads = _checks.integer("threads", self.threads, 0, 4096)
        c.validate()
        return c

    def replace(self, **changes) -> BuildConfig:
        """A copy with some settings changed (unknown names: TypeError naming them)."""
        unknown = sorted(set(changes) - {f.name for f in fields(self)})
        if unknown:
            raise TypeError(
                f"unknown build setting(s) {', '.join(unknown)}; expected: {', '.join(f.name for f in fields(self))}"
            )
        return dataclasses.replace(self, **changes)

    def tree_settings(self) -> dict:
        """The settings the tree depends on, by name (what stats files and tables record)."""
        return {f.name: getattr(self, f.name) for f in fields(self) if f.compare}


def method_from_label(label: str) -> dict:
    """Build settings of a method label as tables and the CLI write them: 'sah32' → method sah
    with 32 bins; every other label is a method name."""
    if label.startswith("sah") and label[3:].isascii() and label[3:].isdigit():  # not 'sah²' (int() refused it)
        return {"method": "sah", "bins": int(label[3:])}
    if label not in METHODS:
        raise ValueError(f"unknown method '{label}'; expected one of: {', '.join(METHODS)}, or sah<B> such as sah32")
    return {"method": label}


def label_settings(label: str, bins: int | None = None) -> dict:
    """method_from_label(label) with `bins` given apart (--bins, a sweep grid's bins) where not None:
    refused where the label gives the bins too ('sah32' with --bins 8 built 8 bins and was called
    sah32: an audit)."""
    settings = method_from_label(label)
    if bins is not None:
        if "bins" in settings:
            raise ValueError(f"method '{label}' gives the bins; give bins or sah<B>, not both")
        settings["bins"] = bins
    return settings
