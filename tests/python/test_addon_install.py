"""The extension zip `make addon` builds (dist/bvhlab.zip): one wheel per Python Blender embeds,
listed in its manifest with the project's one version. That it installs and enables headless,
unregisters without leftovers and enables again is the install group of tests/blender/registry.py
(under bpy 4.2 in test_blender_checks.py; under bpy 5.2 and the Blender binaries 4.3, Python 3.13,
and 5.2, Python 3.14, by `make blender-test`)."""

import re
import tomllib
import zipfile
from pathlib import Path

import blender_checks
import pytest

import bvhlab

ROOT = blender_checks.ROOT
ZIP = blender_checks.ZIP
#: The Pythons Blender embeds: 3.11 (4.2 LTS to 5.0), 3.13 (blender.org's 5.1 and later), 3.14
#: (distribution builds linked to their system Python, as Debian's 5.2). One wheel each: Blender's
#: installer refuses cp311 + one abi3 wheel under 3.13 and 3.14 (tests/blender/checks_versions.py).
BLENDER_PYTHONS = ("cp311", "cp313", "cp314")


def _zip() -> Path:
    assert ZIP.exists(), f"no {ZIP}: `make addon` builds it (make test does; make check a cp311-only one)"
    return ZIP


@pytest.mark.full_zip
def test_zip_has_a_wheel_for_each_blender_python_and_one_version():
    with zipfile.ZipFile(_zip()) as archive:
        manifest = tomllib.loads(archive.read("blender_manifest.toml").decode())
        names = set(archive.namelist())
    version = bvhlab.__version__
    assert manifest["version"] == version
    assert sorted(manifest["wheels"]) == [
        f"./wheels/bvhlab-{version}-{tag}-{tag}-linux_x86_64.whl" for tag in BLENDER_PYTHONS
    ]
    assert all(wheel[2:] in names for wheel in manifest["wheels"]), (manifest["wheels"], names)


def test_version_is_written_once():
    """__init__.py holds it; the in-place manifest (for development) must agree; nothing else
    may spell it out."""
    source = tomllib.loads((ROOT / "addon" / "blender_manifest.toml").read_text())
    assert source["version"] == bvhlab.__version__ and "wheels" not in source
    assert "version" in tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["dynamic"]
    assert not re.search(r"project\(bvhlab VERSION \d", (ROOT / "CMakeLists.txt").read_text())


#: The newest glibc and libstdc++ (GCC 12's) the wheels may ask for: Ubuntu 22.04, Debian 12,
#: Fedora 36, RHEL 9 and later have them. Blender itself runs from glibc 2.28; on older systems the
#: core cannot load (the README says so).
MAX_GLIBC = (2, 34)
MAX_GLIBCXX = (3, 4, 30)


@pytest.mark.full_zip
def test_wheels_load_on_glibc_2_34_and_gcc_12_libstdcxx():
    """Each wheel's compiled core asks only for glibc symbols up to MAX_GLIBC and libstdc++ symbols
    up to MAX_GLIBCXX, so it loads in Blender on the systems the README names. The cp313 and cp314
    wheels are built in Debian 13 and sid roots, whose GCC 14/16 and glibc 2.41/2.43 raise both if
    left alone (glibc 2.38 renamed strtoul's symbol: one std::stoul did that once; 2.43 gave sqrtf,
    atan2f and acosf new versions): they are built with GCC 12, and scripts/wheel_glibc_compat.h
    binds libm's functions to their old versions."""
    import subprocess
    import tempfile

    with zipfile.ZipFile(_zip()) as archive, tempfile.TemporaryDirectory() as tmp:
        wheels = [n for n in archive.namelist() if n.endswith(".whl")]
        assert len(wheels) == len(BLENDER_PYTHONS)
        for wheel in wheels:
            archive.extract(wheel, tmp)
            with zipfile.ZipFile(Path(tmp) / wheel) as inner:
                core = next(n for n in inner.namelist() if re.search(r"_core\..*\.so$", n))
                inner.extract(core, tmp)
            symbols = subprocess.run(
                ["objdump", "-T", str(Path(tmp) / core)], capture_output=True, text=True, check=True
            ).stdout
            needed = {tuple(int(x) for x in v.split(".")) for v in re.findall(r"GLIBC_(\d+\.\d+(?:\.\d+)?)", symbols)}
            assert max(needed) <= MAX_GLIBC, f"{wheel} needs glibc {max(needed)}: " + ", ".join(
                line.split()[-1]
                for line in symbols.splitlines()
                if "GLIBC_" in line
                and tuple(int(x) for x in re.search(r"GLIBC_([\d.]+)", line).group(1).split(".")) > MAX_GLIBC
            )
            cxx = {tuple(int(x) for x in v.split(".")) for v in re.findall(r"GLIBCXX_(\d+\.\d+(?:\.\d+)?)", symbols)}
            assert max(cxx) <= MAX_GLIBCXX, f"{wheel} needs libstdc++ GLIBCXX_{'.'.join(map(str, max(cxx)))}"
