"""Whether the bvhlab package Python imports is the one this extension's zip bundles for it.

Blender installs an extension's wheel again only where its name changes, and a Python module stays
loaded until Blender quits: a zip rebuilt at the same version, installed over the one before, ran
its new add-on code on the old core, also after a restart (probe). So each wheel's version carries
the digest of its package (`+g` and LABEL_DIGITS hex digits, wheel_label; scripts/build_addon.py relabel_wheel) and
Blender replaces it; the zip carries the digests (DIGESTS, package_digest over the wheel's
entries). At register the add-on takes the same digest of the package installed: where it differs
from the zip's, the installed one is another build's; where it differs from the digest taken when
bvhlab was first checked in this Blender (kept on the module, which outlives the add-on's
reloads), the files were replaced under the loaded core, and a restart loads them. No bpy here: the
build script uses it."""

from __future__ import annotations

import hashlib
import json
import sys
from collections.abc import Iterable
from pathlib import Path

#: The zip's file of {python tag: digest of that wheel's bvhlab package}.
DIGESTS = "wheel_digests.json"

#: Hex digits of a package's digest in its wheel's local version label.
LABEL_DIGITS = 16


def wheel_label(digest: str) -> str:
    """A wheel's local version label for its package's digest: "g" and LABEL_DIGITS hex digits (the
    letter first, so that PEP 440's normalisation never drops a leading zero of all-digit labels)."""
    return "g" + digest[:LABEL_DIGITS]


MISMATCH = (
    "The bvhlab core installed is not the one this extension bundles: remove the extension, "
    "restart Blender and install it again"
)
RESTART = (
    "The bvhlab core was updated while Blender ran, and the one loaded is the one before: restart Blender to load it"
)

#: The bvhlab module's attribute holding its package's digest as first checked in this process.
_LOADED_DIGEST = "_addon_loaded_digest"


def package_digest(files: Iterable[tuple[str, bytes]]) -> str:
    """sha256 of a package's files, (name relative to site-packages, "bvhlab/...", and bytes),
    in the order of their names: a wheel's entries or the files installed from it."""
    digest = hashlib.sha256()
    for name, data in sorted(files):
        digest.update(name.encode() + b"\0" + len(data).to_bytes(8, "little"))
        digest.update(data)
    return digest.hexdigest()


def installed_files(package: Path) -> Iterable[tuple[str, bytes]]:
    """The files of an installed package folder as package_digest takes them (bytecode caches,
    which Python writes there itself, left out)."""
    for path in package.rglob("*"):
        if path.is_file() and "__pycache__" not in path.parts and path.suffix != ".pyc":
            yield path.relative_to(package.parent).as_posix(), path.read_bytes()


def python_tag() -> str:
    """The running Python's wheel tag (cp311, cp313, cp314): which of the zip's wheels is its own."""
    return f"cp{sys.version_info.major}{sys.version_info.minor}"


def core_mismatch(addon_folder: Path) -> str:
    """MISMATCH where the installed bvhlab package is not the one the zip at `addon_folder` bundles
    for this Python, RESTART where it is but was installed after the loaded one; "" where the
    loaded package is the zip's, or where there is no zip's digest to compare with (the add-on
    used in place, during development)."""
    path = addon_folder / DIGESTS
    if not path.is_file():
        return ""
    expected = json.loads(path.read_text()).get(python_tag())
    if expected is None:
        return ""
    import bvhlab

    found = package_digest(installed_files(Path(bvhlab.__file__).parent))
    loaded = getattr(bvhlab, _LOADED_DIGEST, None)
    if loaded is None:
        setattr(bvhlab, _LOADED_DIGEST, found)
        loaded = found
    if found != expected:
        return MISMATCH
    return "" if loaded == found else RESTART
