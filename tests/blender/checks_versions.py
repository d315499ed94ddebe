"""Which of the zip's wheels a Blender takes, by the Python it embeds: 3.11 (4.2 LTS to 5.0), 3.13
(blender.org's 5.1 and later) or 3.14 (distribution builds, linked to their system Python). The zip
carries one wheel per Python (PYTHON_TAGS in scripts/build_addon.py); these checks show the
installer picks this Python's, and why the zip does not carry one stable-ABI (abi3) wheel for 3.12
and later instead. Run with the install group (tests/blender/run.py), the probe before the install.
"""

from __future__ import annotations

import importlib.machinery
import re
import sys
import tempfile
import zipfile
from pathlib import Path

import bpy

PROBE_REPO = "bvhlab_abi3_probe"


def check_installed_core_is_this_pythons() -> None:
    """After the zip's install: exactly one compiled core, the one built for this Python."""
    site = Path(bpy.utils.user_resource("EXTENSIONS", path=".local"))
    cores = sorted(p.name for p in site.rglob("bvhlab/_core*.so"))
    want = "_core" + importlib.machinery.EXTENSION_SUFFIXES[0]  # _core.cpython-314-x86_64-linux-gnu.so
    assert cores == [want], f"installed {cores} under {site}; Python {sys.version.split()[0]} loads {want}"


def _abi3_probe(zip_path: Path, out: Path) -> Path:
    """The built zip, its manifest listing the cp311 wheel and one named cp312-abi3 (a copy of the
    cp313 wheel: the installer decides from the names, before it opens a wheel)."""
    probe = out / "bvhlab_abi3_probe.zip"
    with zipfile.ZipFile(zip_path) as source, zipfile.ZipFile(probe, "w") as target:
        names = source.namelist()
        cp311 = next(n for n in names if re.search(r"-cp311-cp311-linux_x86_64\.whl$", n))
        cp313 = next(n for n in names if re.search(r"-cp313-cp313-linux_x86_64\.whl$", n))
        abi3 = cp313.replace("-cp313-cp313-", "-cp312-abi3-")
        for name in names:
            if name.endswith(".whl") and name != cp311:
                continue
            data = source.read(name)
            if name == "blender_manifest.toml":
                listed = f'wheels = [\n  "./{cp311}",\n  "./{abi3}",\n]\n'
                data = re.sub(r"^wheels = \[.*?\]\n", listed, data.decode(), flags=re.M | re.S).encode()
            target.writestr(name, data)
        target.writestr(abi3, source.read(cp313))
    return probe


def check_abi3_beside_cp311_refused(zip_path: Path) -> None:
    """Under Python 3.12 and later. Blender reads the Pythons an extension supports from its wheels'
    names and drops an abi3 wheel's "any 3.x" when a cp3XY wheel is listed too, so cp311 +
    cp312-abi3 installs but is refused when enabled ("isn't compatible with (3.11)"), though an
    abi3 wheel alone loads and builds there (nanobind's STABLE_ABI, tried on 2026-12-02 in Blender
    4.3, Debian's 5.2.2 and bpy 5.2.3). Should a Blender enable the pair, one abi3 wheel could
    replace cp313 and cp314 (addon/blender_manifest.toml says which wheels the zip carries, and why)."""
    assert sys.version_info >= (3, 12), "the question arises only where an abi3 wheel could load"
    with tempfile.TemporaryDirectory() as tmp:
        probe = _abi3_probe(zip_path, Path(tmp))
        repo = bpy.context.preferences.extensions.repos.new(
            name=PROBE_REPO, module=PROBE_REPO, custom_directory=str(Path(tmp) / "repo"), source="USER"
        )
        try:
            result = bpy.ops.extensions.package_install_files(
                filepath=str(probe), repo=PROBE_REPO, enable_on_install=True
            )
            refusal = None
        except RuntimeError as error:
            result, refusal = None, str(error)
        finally:
            bpy.context.preferences.extensions.repos.remove(repo)
    here = "{}.{}".format(*sys.version_info[:2])
    assert refusal is not None and f"({here}) isn't compatible with (3.11)" in refusal, (
        f"Blender {bpy.app.version_string} on Python {here} did not refuse cp311 + cp312-abi3 as expected "
        f"(result {result}, error {refusal!r}): one abi3 wheel may do for 3.12 and later now"
    )
