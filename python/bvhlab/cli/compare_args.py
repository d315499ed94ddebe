"""Argument types of `bvhlab compare`: each rejects bad input with argparse's own error
("bvhlab compare: error: argument --frames: ...", exit 2) before any work starts."""

from __future__ import annotations

import argparse
from pathlib import Path

from .._checks import OutputPathError, check_writable
from ..build_config import method_from_label
from ..compare.measure import build_settings
from ..compare.protocol import MAX_SAMPLES, MIN_SAMPLES
from .options import checked_build_kwargs, whole_number

DEFAULT_METHODS = "median,mean,midpoint,sah12,sah32"


def sample_count(text: str) -> int:
    """Frames or builds per method: the protocol needs at least MIN_SAMPLES for a spread, and takes
    at most MAX_SAMPLES (issue 39.3)."""
    n = whole_number(text)
    if n < MIN_SAMPLES:
        raise argparse.ArgumentTypeError(
            f"must be at least {MIN_SAMPLES} (the protocol reports a median and its "
            f"spread, which needs {MIN_SAMPLES} samples), got {n}"
        )
    if n > MAX_SAMPLES:
        raise argparse.ArgumentTypeError(
            f"must be at most {MAX_SAMPLES} (more rounds no longer narrow the spread), got {n}"
        )
    return n


def thread_count(text: str) -> int:
    return whole_number(text, 0, 4096, " threads")  # 0: every core


def method_list(text: str) -> list[str]:
    """'median,sah12' → ['median', 'sah12']; empty, unknown or repeated names are errors."""
    labels = [m.strip() for m in text.split(",")]
    if not any(labels):
        raise argparse.ArgumentTypeError(f"no methods given in '{text}' (e.g. median,mean,sah12)")
    if "" in labels:
        raise argparse.ArgumentTypeError(f"empty method name in '{text}'")
    for label in labels:
        try:
            method_from_label(label)
        except ValueError as e:
            raise argparse.ArgumentTypeError(str(e)) from None
        try:  # every setting of the label's build, as the measurement will use it (sah1: one bin)
            checked_build_kwargs(build_settings(label))
        except (ValueError, TypeError) as e:
            raise argparse.ArgumentTypeError(f"{label}: {e}") from None
    repeated = sorted({m for m in labels if labels.count(m) > 1})
    if repeated:
        raise argparse.ArgumentTypeError(f"method given more than once: {', '.join(repeated)}")
    # one build under two names (sah, sah12 and sah012 are one): measured twice, its figures twice
    seen: dict[str, str] = {}
    for label in labels:
        same = seen.setdefault(repr(sorted(build_settings(label).items())), label)
        if same != label:
            raise argparse.ArgumentTypeError(f"{same} and {label} are the same build: give one of them")
    return labels


def method_pair(text: str) -> list[str]:
    """'median,sah12' → two method labels (method_list's checks), exactly two."""
    labels = method_list(text)
    if len(labels) != 2:
        raise argparse.ArgumentTypeError(f"give two methods A,B, got {len(labels)}")
    return labels


def backend_list(text: str) -> list[str]:
    """'cpu,vulkan' → ['cpu', 'vulkan']; 'none' → []."""
    if text.strip() == "none":
        return []
    names = [b.strip() for b in text.split(",")]
    bad = [b for b in names if b not in ("cpu", "vulkan")]
    if bad or not names:
        raise argparse.ArgumentTypeError(f"expected cpu, vulkan, both (cpu,vulkan) or none, got '{text}'")
    return list(dict.fromkeys(names))


def output_dir(text: str) -> Path:
    """A directory to write into: it may exist (as a directory), but neither it nor a folder above it
    may be a file, and the nearest that exists must take new files (checked before any work). The
    path is used as given, never renamed. An empty one is refused (Path("") is the current folder:
    a sweep's files were written there, helper probe)."""
    if not text.strip():
        raise argparse.ArgumentTypeError("the output folder is empty (e.g. --out out/study)")
    path = Path(text)
    if path.exists() and not path.is_dir():
        raise argparse.ArgumentTypeError(
            f"{path} exists and is not a directory (--out names a folder the results are written into)"
        )
    for folder in (path, *path.parents):
        if folder.exists():
            if not folder.is_dir():
                raise argparse.ArgumentTypeError(f"cannot create {path}: {folder} is a file")
            try:
                check_writable(folder, path)
            except OutputPathError as e:
                raise argparse.ArgumentTypeError(str(e)) from None
            break
    return path
