"""Build the installable Blender extension zip (`make addon`), one bvhlab wheel per Python that
Blender embeds (cp311 for Blender 4.2-5.0, cp313 for blender.org's 5.1 and later, cp314 for
distribution builds linked to their system Python, such as Debian's 5.2):

    PYTHON scripts/build_addon.py wheel [--into build/wheels]     # a wheel for the running Python
    .venv/bin/python scripts/build_addon.py package [--wheels build/wheels] [--output-dir dist]

`wheel` builds the bvhlab wheel (the compiled core plus bvhlab.blender) for the interpreter that
runs it, in a CMake build folder of its own (build/wheel-cpXY), so the editable install's build is
never touched; `make addon` runs it with the project's Python 3.11, with Python 3.13 inside the
Debian 13 root and with Python 3.14 inside the Debian sid root (scripts/debian_root.sh).

`package` copies addon/ to build/addon-stage, adds the wheels (one for each of PYTHON_TAGS, all of
the current version), writes the stage's manifest with the version from python/bvhlab/__init__.py
(the one source of the version) and `wheels = [...]`, then validates and packages it with Blender's
extension tool, which ships in the bpy wheel (no Blender binary needed). Prints the zip's path.
Install it with Edit ▸ Preferences ▸ Get Extensions ▸ Install from Disk, or headless with
bpy.ops.extensions.package_install_files(filepath=ZIP, repo="user_default").
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import zipfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
ADDON = ROOT / "addon"


def _core_check():
    """addon/core_check.py, loaded by its path (the add-on's package imports bpy)."""
    spec = importlib.util.spec_from_file_location("bvhlab_core_check", ADDON / "core_check.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


core_check = _core_check()

VERSION_FILE = ROOT / "python" / "bvhlab" / "__init__.py"
#: Included first in each C++ file of a wheel: keeps libm's symbol versions at glibc 2.34's.
GLIBC_COMPAT = ROOT / "scripts" / "wheel_glibc_compat.h"
#: The Pythons Blender embeds: 3.11 in 4.2 LTS to 5.0, 3.13 in blender.org's 5.1, 5.2 LTS and 5.3,
#: 3.14 in distribution builds (Debian sid's 5.2.2). One wheel each, not one stable-ABI (abi3) wheel
#: for 3.12+: Blender's installer refuses cp311 + abi3 on 3.13 and 3.14 (tests/blender/checks_versions.py).
PYTHON_TAGS = ("cp311", "cp313", "cp314")


def project_version() -> str:
    """`__version__` of python/bvhlab/__init__.py, the one place the version is written."""
    found = re.search(r'^__version__ = "([^"]+)"$', VERSION_FILE.read_text(), re.M)
    if found is None:
        raise SystemExit(f'no __version__ = "..." line in {VERSION_FILE}')
    return found.group(1)


def warm_cmake() -> str:
    """CMake's path, after one `cmake -E capabilities` run with no time limit. scikit-build-core
    gives that command 5 s to answer before it declares CMake missing, and the first run of a fresh
    Debian root's CMake, from a cold disk while the other wheels compile, took longer in CI
    ("Could not find CMake with version >=3.22"; scikit-build-core issues 1127 and 1530)."""
    cmake = shutil.which("cmake")
    if cmake is None:
        raise SystemExit("no cmake on PATH: install it (scripts/install_system_packages.sh)")
    subprocess.run([cmake, "-E", "capabilities"], stdout=subprocess.DEVNULL, check=True)
    return cmake


def build_wheel(into: Path) -> Path:
    """The bvhlab wheel for the running Python, copied into `into` (older ones of that tag removed).
    CMAKE_CXX_FLAGS is passed on every configure (a kept build folder picks up a change)."""
    tag = core_check.python_tag()
    cxx_flags = f"{os.environ.get('CXXFLAGS', '')} -include {GLIBC_COMPAT}".strip()
    env = {**os.environ, "CMAKE_EXECUTABLE": warm_cmake()}
    with tempfile.TemporaryDirectory() as tmp:
        subprocess.run(
            [
                sys.executable,
                "-m",
                "pip",
                "wheel",
                str(ROOT),
                "--no-build-isolation",
                "--no-deps",
                "-q",
                "-w",
                tmp,
                f"--config-settings=build-dir=build/wheel-{tag}",
                f"--config-settings=cmake.define.CMAKE_CXX_FLAGS={cxx_flags}",
            ],
            cwd=ROOT,
            env=env,
            check=True,
        )
        built = list(Path(tmp).glob(f"bvhlab-*-{tag}-*.whl"))
        if len(built) != 1:
            raise SystemExit(f"expected one {tag} bvhlab wheel from pip, found {built}")
        into.mkdir(parents=True, exist_ok=True)
        for stale in into.glob(f"bvhlab-*-{tag}-*.whl"):
            stale.unlink()
        return Path(shutil.copy2(built[0], into))


def wheels_for_version(wheels_dir: Path, version: str, tags=PYTHON_TAGS) -> list[Path]:
    """One wheel per tag of `tags`, of this version; a clear error naming what is missing."""
    found, missing = [], []
    for tag in tags:
        matches = sorted(wheels_dir.glob(f"bvhlab-{version}-{tag}-{tag}-*.whl"))
        if len(matches) != 1:
            missing.append(f"{tag} ({len(matches)} found)")
        else:
            found.append(matches[0])
    if missing:
        raise SystemExit(
            f"{wheels_dir} needs exactly one bvhlab-{version} wheel for each of {', '.join(tags)}; "
            f"missing: {', '.join(missing)}. `make addon` builds them all (cp313 in the Debian 13 root, "
            "cp314 in the sid one)."
        )
    return found


def stage_manifest(source: str, version: str, wheel_names: list[str]) -> str:
    """The source manifest with the project's version and the bundled wheels filled in."""
    if re.search(r"^wheels\s*=", source, re.M):
        raise SystemExit("addon/blender_manifest.toml must not list wheels: scripts/build_addon.py writes them")
    text, count = re.subn(r'^version = "[^"]*"$', f'version = "{version}"', source, flags=re.M)
    if count != 1:
        raise SystemExit('addon/blender_manifest.toml needs one top-level `version = "..."` line')
    wheels = "wheels = [\n" + "".join(f'  "./wheels/{name}",\n' for name in wheel_names) + "]\n"
    text, count = re.subn(r"^(platforms = .*\n)", lambda m: m.group(1) + wheels, text, flags=re.M)
    if count != 1:
        raise SystemExit("addon/blender_manifest.toml needs a `platforms = [...]` line")
    return text


def wheel_tag(wheel: Path) -> str:
    """The Python tag of a wheel's file name (cp311 of bvhlab-0.1.0-cp311-cp311-linux_x86_64.whl)."""
    return wheel.name.split("-")[2]


def wheel_digests(wheels: list[Path]) -> dict[str, str]:
    """{python tag: digest of the wheel's bvhlab package} (addon/core_check.py, which the add-on
    compares with the package it imports)."""
    digests = {}
    for wheel in wheels:
        tag = wheel_tag(wheel)
        with zipfile.ZipFile(wheel) as archive:
            files = [
                (n, archive.read(n)) for n in archive.namelist() if n.startswith("bvhlab/") and not n.endswith("/")
            ]
        digests[tag] = core_check.package_digest(files)
    return digests


def relabel_wheel(wheel: Path, into: Path, label: str) -> Path:
    """A copy of `wheel` in `into` whose version carries the local label `+label` (PEP 440; one
    there before is replaced): in its file name, its .dist-info folder, METADATA's Version and
    RECORD, whose rows are made again (csv, sha256 in unpadded urlsafe base64, size).

    Blender installs an extension's wheel again only where the name of its .dist-info folder
    changes (`apply_action` in _bpy_internal/extensions/wheel_manager.py keeps a folder of the
    same name), so a zip rebuilt at the same version, installed over the one before, kept the
    old core for good; labelled with its package's digest, each build's wheel is a new one."""
    import base64
    import csv
    import hashlib
    import io

    name, version, *tags = wheel.name.split("-")
    release = version.split("+")[0]
    labelled = f"{release}+{label}"
    old_info, new_info = f"{name}-{version}.dist-info/", f"{name}-{labelled}.dist-info/"
    record = new_info + "RECORD"
    out = into / "-".join([name, labelled, *tags])
    with zipfile.ZipFile(wheel) as source:
        entries = []  # (the entry's ZipInfo, its new name, its bytes), RECORD's last
        for info in source.infolist():
            data = source.read(info)
            renamed = info.filename
            if renamed.startswith(old_info):
                renamed = new_info + renamed[len(old_info) :]
            if renamed == new_info + "METADATA":
                data, count = re.subn(rb"^Version: .*$", f"Version: {labelled}".encode(), data, count=1, flags=re.M)
                if count != 1:
                    raise SystemExit(f"{wheel.name}: METADATA has no Version line")
            entries.append((info, renamed, data))
    entries.sort(key=lambda entry: entry[1] == record)
    if entries[-1][1] != record:
        raise SystemExit(f"{wheel.name} has no {old_info}RECORD")
    rows = io.StringIO()
    writer = csv.writer(rows, lineterminator="\n")
    for _, renamed, data in entries[:-1]:
        digest = base64.urlsafe_b64encode(hashlib.sha256(data).digest()).rstrip(b"=").decode()
        writer.writerow([renamed, f"sha256={digest}", len(data)])
    writer.writerow([record, "", ""])
    entries[-1] = (entries[-1][0], record, rows.getvalue().encode())
    with zipfile.ZipFile(out, "w", zipfile.ZIP_DEFLATED) as target:
        for info, renamed, data in entries:
            entry = zipfile.ZipInfo(renamed, date_time=info.date_time)
            entry.external_attr = info.external_attr
            entry.compress_type = zipfile.ZIP_DEFLATED
            target.writestr(entry, data)
    return out


def stage(wheels: list[Path], version: str) -> Path:
    """addon/ copied to build/addon-stage with the wheels, each labelled with the digest of its
    package (relabel_wheel), and the generated manifest."""
    staged = ROOT / "build" / "addon-stage" / "bvhlab"
    shutil.rmtree(staged.parent, ignore_errors=True)
    shutil.copytree(ADDON, staged, ignore=shutil.ignore_patterns("__pycache__", "wheels", "*.pyc"))
    (staged / "wheels").mkdir()
    digests = wheel_digests(wheels)
    labelled = [relabel_wheel(w, staged / "wheels", core_check.wheel_label(digests[wheel_tag(w)])) for w in wheels]
    (staged / core_check.DIGESTS).write_text(json.dumps(digests, indent=1) + "\n")
    manifest = staged / "blender_manifest.toml"
    manifest.write_text(stage_manifest(manifest.read_text(), version, [w.name for w in labelled]))
    return staged


def extension_tool() -> Path:
    """blender_ext.py from the installed bpy wheel (found without importing bpy)."""
    import importlib.util

    spec = importlib.util.find_spec("bpy")
    if spec is None or spec.origin is None:
        raise SystemExit("bpy is not installed in this Python; use the project's .venv/bin/python")
    tools = sorted(Path(spec.origin).parent.glob("*/scripts/addons_core/bl_pkg/cli/blender_ext.py"))
    if not tools:
        raise SystemExit(f"Blender's extension tool (blender_ext.py) is missing under {Path(spec.origin).parent}")
    return tools[-1]


def package(wheels_dir: Path, output_dir: Path, tags=PYTHON_TAGS) -> Path:
    version = project_version()
    staged = stage(wheels_for_version(wheels_dir, version, tags), version)
    tool = [sys.executable, str(extension_tool())]
    subprocess.run([*tool, "validate", str(staged)], check=True, stdout=subprocess.DEVNULL)
    output_dir.mkdir(parents=True, exist_ok=True)
    for stale in output_dir.glob("bvhlab-*.zip"):
        stale.unlink()
    subprocess.run(
        [*tool, "build", "--source-dir", str(staged), "--output-dir", str(output_dir)],
        check=True,
        stdout=subprocess.DEVNULL,
    )
    zips = list(output_dir.glob(f"bvhlab-{version}*.zip"))
    if len(zips) != 1:
        raise SystemExit(f"expected one bvhlab-{version} zip in {output_dir}, found {zips}")
    return zips[0]


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="command", required=True)
    wheel = sub.add_parser("wheel", help="build the bvhlab wheel for the running Python")
    wheel.add_argument("--into", type=Path, default=ROOT / "build" / "wheels")
    pack = sub.add_parser("package", help="stage addon/ with the wheels and build the zip")
    pack.add_argument("--wheels", type=Path, default=ROOT / "build" / "wheels")
    pack.add_argument("--output-dir", type=Path, default=ROOT / "dist")
    pack.add_argument(
        "--tags",
        nargs="+",
        choices=PYTHON_TAGS,
        default=list(PYTHON_TAGS),
        help="the Pythons whose wheels go in (default: all; make check packs cp311 alone)",
    )
    args = ap.parse_args(argv)
    if args.command == "wheel":
        print(build_wheel(args.into.resolve()))
    else:
        print(package(args.wheels.resolve(), args.output_dir.resolve(), tuple(args.tags)))


if __name__ == "__main__":
    main()
