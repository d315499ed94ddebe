"""The extension zip `make addon` builds (dist/bvhlab.zip): one wheel per Python Blender embeds,
listed in its manifest with the project's one version; it installs and enables headless under
bpy 4.2, unregisters without leftovers, and enables again (in a child process with its own user
folder). The same zip is installed under bpy 5.2 and a Blender binary by `make blender-test`."""

import re
import tomllib
import zipfile
from pathlib import Path

import blender_checks

import bvhlab

ROOT = Path(__file__).resolve().parents[2]
ZIP = ROOT / "dist" / "bvhlab.zip"


def _zip() -> Path:
    assert ZIP.exists(), f"no {ZIP}: `make addon` builds it (make test does)"
    return ZIP


def test_zip_has_a_wheel_for_each_blender_python_and_one_version():
    with zipfile.ZipFile(_zip()) as archive:
        manifest = tomllib.loads(archive.read("blender_manifest.toml").decode())
        names = set(archive.namelist())
    version = bvhlab.__version__
    assert manifest["version"] == version
    assert sorted(manifest["wheels"]) == [
        f"./wheels/bvhlab-{version}-{tag}-{tag}-linux_x86_64.whl" for tag in ("cp311", "cp313")
    ]
    assert all(wheel[2:] in names for wheel in manifest["wheels"]), (manifest["wheels"], names)


def test_version_is_written_once():
    """__init__.py holds it; the in-place manifest (for development) must agree; nothing else
    may spell it out."""
    source = tomllib.loads((ROOT / "addon" / "blender_manifest.toml").read_text())
    assert source["version"] == bvhlab.__version__ and "wheels" not in source
    assert "version" in tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["dynamic"]
    assert not re.search(r"project\(bvhlab VERSION \d", (ROOT / "CMakeLists.txt").read_text())


def test_built_zip_installs_enables_and_unregisters():
    blender_checks.run_groups("install", zip_path=_zip())
