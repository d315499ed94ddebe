"""A sweep's SPEC.toml: the scenes and the grid of build settings, read and checked before any work.

    scenes = ["gen:knot", "sponza", "models/*.ply", "extra/bunny.obj"]   # names, files, globs
    [grid]                    # each a value or a list; every combination is one cell
    method = ["median", "sah"]  # or "sah32": method sah with 32 bins, as --method reads it
    bins = [12, 32]
    bin_bounds = "box"
    axis = "auto"
    max_leaf_size = [1, 4]
    sah_block = 1
    traversal = "wide"        # of the timed intersect (bvhlab.TRAVERSALS)
    [rays]
    count = 100000            # fixed random rays per cell
    seed = 1
    repeats = 3               # timed passes over them; the table has the median
    [report]
    baseline = "median"       # the method the summary's ratios divide by (default: the grid's first)

Settings a grid leaves out keep BuildConfig's defaults. Globs and relative paths are relative to the
spec's folder; a glob takes the scene files it matches (mesh files, .blend, .npz; not folders),
and one that matches none is an error (ValueError naming it). A name that is a file is that file,
even where it reads as a glob ("scan[1].obj")."""

from __future__ import annotations

import glob
import itertools
import os
import tomllib
from dataclasses import dataclass, fields
from pathlib import Path

from .. import _checks
from ..build_config import BuildConfig, label_settings, method_from_label
from ..library import is_scene_file
from ..ray_query import TRAVERSALS

#: The grid's keys: BuildConfig's tree settings (threads is the sweep's: one per worker) and traversal.
GRID_KEYS = tuple(f.name for f in fields(BuildConfig) if f.compare) + ("traversal",)
DEFAULT_RAYS, MAX_RAYS = 100_000, 100_000_000
DEFAULT_REPEATS, MAX_REPEATS = 3, 100


@dataclass(frozen=True)
class Setting:
    """One point of the grid: the tree's settings and the traversal its rays are timed with."""

    config: BuildConfig
    traversal: str

    def columns(self) -> dict:
        return {**self.config.tree_settings(), "traversal": self.traversal}


@dataclass(frozen=True)
class SweepSpec:
    scenes: tuple[str, ...]  # names as given, files and glob matches as paths
    settings: tuple[Setting, ...]
    rays: int = DEFAULT_RAYS
    ray_seed: int = 1
    repeats: int = DEFAULT_REPEATS
    baseline: str = "median"  # a method of the grid: summary.md and its plot divide by its cells


#: The largest seed a sweep takes: the table's columns are 64-bit signed (Parquet's int64); a seed
#: of 2^63 ran every cell, then failed to write the table (and every rerun the same way).
MAX_SEED = 2**63 - 1


def read_spec(path) -> SweepSpec:
    """The spec at `path`, checked (ValueError naming the file and the problem)."""
    path = Path(path)
    _checks.input_file(path, "sweep spec", ValueError)  # a FIFO blocked the read
    try:
        doc = tomllib.loads(path.read_text())
    except tomllib.TOMLDecodeError as e:
        raise ValueError(f"{path}: not valid TOML: {e}") from None
    except UnicodeDecodeError:
        raise ValueError(f"{path}: not a text file") from None
    _only(path, "the spec", doc, ("scenes", "grid", "rays", "report"))
    scenes = _scenes(path, doc.get("scenes"))
    settings = _grid(path, doc.get("grid", {}))
    rays = doc.get("rays", {})
    _only(path, "[rays]", rays, ("count", "seed", "repeats"))
    count, seed, repeats = rays.get("count", DEFAULT_RAYS), rays.get("seed", 1), rays.get("repeats", DEFAULT_REPEATS)
    if not _whole(count) or not 1 <= count <= MAX_RAYS:
        raise ValueError(f"{path}: [rays] count must be a whole number from 1 to {MAX_RAYS}, got {count!r}")
    if not _whole(seed) or not 0 <= seed <= MAX_SEED:
        raise ValueError(f"{path}: [rays] seed must be a whole number from 0 to {MAX_SEED}, got {seed!r}")
    if not _whole(repeats) or not 1 <= repeats <= MAX_REPEATS:
        raise ValueError(f"{path}: [rays] repeats must be a whole number from 1 to {MAX_REPEATS}, got {repeats!r}")
    return SweepSpec(scenes, settings, count, seed, repeats, _baseline(path, doc.get("report", {}), settings))


def _baseline(path: Path, report, settings: tuple[Setting, ...]) -> str:
    _only(path, "[report]", report, ("baseline",))
    methods = list(dict.fromkeys(s.config.method for s in settings))
    baseline = report.get("baseline", methods[0])
    if baseline not in methods:
        try:  # a label of a method with its bins ("sah32")
            named = isinstance(baseline, str) and "bins" in method_from_label(baseline)
        except ValueError:
            named = False
        hint = " (the baseline is a method, 'sah', whose cells the summary divides by)" if named else ""
        raise ValueError(
            f"{path}: [report] baseline {baseline!r} is not a method of the grid: {', '.join(methods)}{hint}"
        )
    return baseline


def _whole(value) -> bool:
    return isinstance(value, int) and not isinstance(value, bool)


def _only(path: Path, where: str, table, allowed: tuple[str, ...]) -> None:
    if not isinstance(table, dict):
        raise ValueError(f"{path}: {where} must be a table")
    unknown = sorted(set(table) - set(allowed))
    if unknown:
        raise ValueError(f"{path}: unknown key(s) in {where}: {', '.join(unknown)}; expected: {', '.join(allowed)}")


def _scenes(path: Path, entries) -> tuple[str, ...]:
    if isinstance(entries, str):
        entries = [entries]
    if not entries or not isinstance(entries, list) or not all(isinstance(e, str) for e in entries):
        raise ValueError(f"{path}: scenes must be a non-empty list of names, files or globs")
    out: list[str] = []
    folder = path.parent.resolve()
    for entry in entries:
        # a file of that name is that file, brackets and all ("scan[1].obj" read scan1.obj: an audit)
        if glob.has_magic(entry) and not os.path.isfile(folder / entry):  # (False for a name too long)
            # matched under the spec's folder, whose own name is no pattern (a spec in "exp[2]"
            # swept exp2's files, or none: an audit)
            found = sorted(str(folder / m) for m in glob.glob(entry, root_dir=folder, recursive=True))
            # the scene files among them ("models/*" beside a readme.txt made a row "no scene"; a
            # folder named "parts.obj" a row "is a folder")
            matches = [m for m in found if is_scene_file(m) and os.path.isfile(m)]
            if not matches:
                what = f"no scene file (of {len(found)} files)" if found else "no file"
                raise ValueError(f"{path}: the scene glob '{entry}' matches {what}")
            out.extend(matches)
        elif is_scene_file(entry):
            out.append(str(folder / entry))  # a missing file becomes the cell's error row
        else:
            out.append(entry)
    for scene in out:  # the table and summary are UTF-8: refused now, not after every cell ran (an audit)
        try:
            scene.encode("utf-8")
        except UnicodeEncodeError:
            shown = os.fsencode(scene).decode("utf-8", "backslashreplace")
            raise ValueError(f"{path}: the scene file name '{shown}' is not UTF-8: rename it") from None
    return tuple(dict.fromkeys(out))  # each scene once, in the order given


def _settings(values: dict) -> dict:
    """A grid point's build settings, a method label read as --method reads it ("sah12": method sah
    with 12 bins; it was refused here)."""
    method = values.get("method")
    if not isinstance(method, str):
        return values
    return {**values, **label_settings(method, values.get("bins"))}


def _grid(path: Path, grid) -> tuple[Setting, ...]:
    _only(path, "[grid]", grid, GRID_KEYS)
    axes = {key: value if isinstance(value, list) else [value] for key, value in grid.items()}
    for key, values in axes.items():
        if not values:
            raise ValueError(f"{path}: [grid] {key} is an empty list")
    traversals = axes.pop("traversal", ["wide"])
    settings = []
    for combination in itertools.product(*axes.values()):
        try:
            config = BuildConfig(**_settings(dict(zip(axes, combination))))
        except (TypeError, ValueError) as e:
            raise ValueError(f"{path}: [grid] {e}") from None
        if config.seed > MAX_SEED:
            raise ValueError(f"{path}: [grid] seed must be at most {MAX_SEED} in a sweep, got {config.seed}")
        for traversal in traversals:
            if traversal not in TRAVERSALS:
                raise ValueError(f"{path}: [grid] unknown traversal {traversal!r}; expected: {', '.join(TRAVERSALS)}")
            settings.append(Setting(config, traversal))
    return tuple(dict.fromkeys(settings))
