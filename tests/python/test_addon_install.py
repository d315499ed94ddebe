"""The extension zip `make addon` builds (dist/bvhlab.zip): one wheel per Python Blender embeds,
listed in its manifest with the project's one version. That it installs and enables headless,
unregisters without leftovers and enables again is the install group of tests/blender/registry.py
(under bpy 4.2 in test_blender_checks.py; under bpy 5.2 and the Blender binaries 4.3, Python 3.13,
and 5.2, Python 3.14, by `make blender-test`)."""

import json
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
    labels = {tag: "g" + digest[:16] for tag, digest in _digests().items()}
    assert sorted(manifest["wheels"]) == sorted(
        f"./wheels/bvhlab-{version}+{labels[tag]}-{tag}-{tag}-linux_x86_64.whl" for tag in BLENDER_PYTHONS
    )
    assert all(wheel[2:] in names for wheel in manifest["wheels"]), (manifest["wheels"], names)


def _digests() -> dict[str, str]:
    with zipfile.ZipFile(_zip()) as archive:
        return json.loads(archive.read("wheel_digests.json"))


@pytest.mark.full_zip
def test_each_wheel_is_labelled_with_its_package_and_its_record_holds():
    """Blender installs a wheel again only where its .dist-info folder's name changes, so each
    wheel's version carries the digest of its bvhlab package (scripts/build_addon.py
    relabel_wheel): the digest recomputed here from the wheel's files (sha256 over name, size and
    bytes in name order, as addon/core_check.py takes it), the .dist-info folder and METADATA's
    Version carrying it, and RECORD naming every other entry with its sha256 and size."""
    import base64
    import csv
    import hashlib
    import io

    expected = _digests()
    with zipfile.ZipFile(_zip()) as archive:
        wheels = [n for n in archive.namelist() if n.endswith(".whl")]
        for name in wheels:
            tag = name.split("-")[2]
            with zipfile.ZipFile(io.BytesIO(archive.read(name))) as wheel:
                files = {n: wheel.read(n) for n in wheel.namelist() if not n.endswith("/")}
            digest = hashlib.sha256()
            for path in sorted(n for n in files if n.startswith("bvhlab/")):
                digest.update(path.encode() + b"\0" + len(files[path]).to_bytes(8, "little") + files[path])
            assert digest.hexdigest() == expected[tag], name
            labelled = f"{bvhlab.__version__}+g{expected[tag][:16]}"
            info = f"bvhlab-{labelled}.dist-info/"
            assert f"Version: {labelled}\n" in files[info + "METADATA"].decode(), name
            rows = list(csv.reader(io.StringIO(files[info + "RECORD"].decode())))
            assert sorted(r[0] for r in rows) == sorted(files), name
            for path, hashed, size in rows:
                if path == info + "RECORD":
                    assert (hashed, size) == ("", ""), name
                    continue
                sha = base64.urlsafe_b64encode(hashlib.sha256(files[path]).digest()).rstrip(b"=").decode()
                assert (hashed, int(size)) == (f"sha256={sha}", len(files[path])), (name, path)


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
