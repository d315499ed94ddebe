"""Build the installable Blender extension zip (`make addon`):

    .venv/bin/python scripts/build_addon.py [--output-dir dist]

1. builds the bvhlab wheel (the compiled core plus bvhlab.blender) in its own CMake build folder,
   build/wheel, so the editable install's build folder is never touched;
2. puts it in addon/wheels/ under the name addon/blender_manifest.toml lists;
3. validates and packages addon/ with Blender's extension tool, which ships in the bpy wheel
   (no Blender binary needed).
Prints the path of the zip. Install it with Edit ▸ Preferences ▸ Get Extensions ▸ Install from
Disk, or headless with bpy.ops.extensions.package_install_files(filepath=ZIP, repo="user_default").
"""
from __future__ import annotations

import argparse
import shutil
import subprocess
import sys
import tempfile
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
ADDON = ROOT / "addon"
WHEEL_BUILD_DIR = "build/wheel"


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


def manifest_wheel() -> Path:
    """The one wheel path addon/blender_manifest.toml lists."""
    manifest = tomllib.loads((ADDON / "blender_manifest.toml").read_text())
    wheels = manifest.get("wheels", [])
    if len(wheels) != 1:
        raise SystemExit(f"addon/blender_manifest.toml must list exactly one wheel, found {wheels}")
    return ADDON / wheels[0]


def build_wheel(into: Path) -> Path:
    subprocess.run([sys.executable, "-m", "pip", "wheel", str(ROOT), "--no-build-isolation", "--no-deps",
                    "-q", "-w", str(into), f"--config-settings=build-dir={WHEEL_BUILD_DIR}"],
                   cwd=ROOT, check=True)
    wheels = list(into.glob("bvhlab-*.whl"))
    if len(wheels) != 1:
        raise SystemExit(f"expected one bvhlab wheel from pip, found {wheels}")
    return wheels[0]


def place_wheel(wheel: Path) -> Path:
    """Copy the wheel to the manifest's path (removing stale wheels); refuse a name mismatch, which
    would mean the version changed without the manifest."""
    target = manifest_wheel()
    if wheel.name != target.name:
        raise SystemExit(f"pip built {wheel.name} but addon/blender_manifest.toml lists {target.name}: "
                         f"update the manifest's `wheels` (and `version`)")
    target.parent.mkdir(exist_ok=True)
    for stale in target.parent.glob("*.whl"):
        stale.unlink()
    shutil.copy2(wheel, target)
    return target


def package(output_dir: Path) -> Path:
    tool = [sys.executable, str(extension_tool())]
    subprocess.run([*tool, "validate", str(ADDON)], check=True)
    output_dir.mkdir(parents=True, exist_ok=True)
    subprocess.run([*tool, "build", "--source-dir", str(ADDON), "--output-dir", str(output_dir)], check=True)
    version = tomllib.loads((ADDON / "blender_manifest.toml").read_text())["version"]
    zips = list(output_dir.glob(f"bvhlab-{version}*.zip"))
    if len(zips) != 1:
        raise SystemExit(f"expected one bvhlab-{version} zip in {output_dir}, found {zips}")
    return zips[0]


def build_addon(output_dir: Path) -> Path:
    """Steps 1-3 of the module docstring; returns the zip's path."""
    with tempfile.TemporaryDirectory() as tmp:
        place_wheel(build_wheel(Path(tmp)))
    return package(output_dir)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--output-dir", type=Path, default=ROOT / "dist")
    args = ap.parse_args(argv)
    print(build_addon(args.output_dir.resolve()))


if __name__ == "__main__":
    main()
