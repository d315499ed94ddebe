"""The built extension zip installs and enables headless, unregisters cleanly, and enables again.
Run in a process of its own with BLENDER_USER_RESOURCES pointing at a temporary folder
(tests/blender/run.py --only install --zip dist/bvhlab-<version>.zip)."""

from __future__ import annotations

import sys
from pathlib import Path

import bpy
import harness

MODULE = f"bl_ext.user_default.{harness.EXTENSION_ID}"
CLASS_NAMES = ("BVHLAB_OT_build", "BVHLAB_OT_render", "BVHLAB_OT_export_stats", "BVHLAB_OT_compare", "BVHLAB_PT_main")


def _registered() -> dict[str, bool]:
    """What registering adds, each as present or not."""
    found = {name: getattr(bpy.types, name, None) is not None for name in CLASS_NAMES}
    found["Scene.bvhlab"] = hasattr(bpy.types.Scene, "bvhlab")
    found["Object.bvhlab_analytic_sphere"] = hasattr(bpy.types.Object, "bvhlab_analytic_sphere")
    found["load_pre handler"] = any(getattr(h, "__module__", "").startswith(MODULE) for h in bpy.app.handlers.load_pre)
    package = sys.modules.get(MODULE)
    found["draw handler"] = package is not None and package.overlay.handler_installed()
    return found


def _check_the_core_is_the_bundled_one(site: Path) -> None:
    """The add-on compares the bvhlab package imported with the zip's digest of its wheel's
    (addon/core_check.py): no warning for the wheel just installed; a package that differs (a
    rebuilt zip of the same version installed over an older one: its old core stayed loaded, and
    Blender kept its wheel) is named. Under the bpy module the venv's own bvhlab may be the one
    imported, which is not the bundled one: only its wheel's copy is compared."""
    import bvhlab

    package = sys.modules[MODULE]
    check = sys.modules[f"{MODULE}.core_check"]
    installed = Path(bvhlab.__file__).resolve().parent
    if not installed.is_relative_to(site.resolve()):
        installed = next(site.rglob("bvhlab/__init__.py")).parent
        assert check.package_digest(check.installed_files(installed)) == _bundled_digest(package, check)
        return
    assert package.state.core_warning == "", package.state.core_warning
    assert check.core_mismatch(Path(package.__file__).parent) == ""
    marker = installed / "probe_marker.txt"  # the package as another build left it
    marker.write_text("another build")
    try:
        assert check.core_mismatch(Path(package.__file__).parent) == check.MISMATCH
    finally:
        marker.unlink()


def _bundled_digest(package, check) -> str:
    import json

    digests = json.loads((Path(package.__file__).parent / check.DIGESTS).read_text())
    return digests[check.python_tag()]


def _build_default_scene() -> None:
    harness.boxes_scene()
    assert bpy.ops.bvhlab.build() == {"FINISHED"}
    assert sys.modules[MODULE].state.tree_for(bpy.context.scene).bvh.stats["primitives"] == 36


def check_install_enable_disable(zip_path: Path) -> None:
    assert zip_path.exists(), f"no extension zip at {zip_path} (scripts/build_addon.py builds it)"
    result = bpy.ops.extensions.package_install_files(
        filepath=str(zip_path), repo="user_default", enable_on_install=True
    )
    assert result == {"FINISHED"}, result
    assert MODULE in bpy.context.preferences.addons, "installed but not enabled"
    # registering reads the core's names, defaults and limits (addon/properties.py); under the bpy
    # module the venv's editable bvhlab may be the one found first, under a Blender binary the wheel's
    assert "bvhlab" in sys.modules, "registering should have read the core's settings"
    assert all(_registered().values()), _registered()
    site = Path(bpy.utils.user_resource("EXTENSIONS", path=".local"))
    assert list(site.rglob("bvhlab/_core*.so")), f"the bundled wheel was not installed under {site}"
    assert list(site.rglob("bvhlab/blender/export.py")), "the wheel lacks bvhlab.blender"
    _check_the_core_is_the_bundled_one(site)
    harness.enable(MODULE)
    _build_default_scene()

    bpy.ops.preferences.addon_disable(module=MODULE)
    left = {name: present for name, present in _registered().items() if present}
    assert not left, f"still registered after unregister: {left}"
    try:
        bpy.ops.bvhlab.build()
    except (AttributeError, RuntimeError):
        pass
    else:
        raise AssertionError("bvhlab.build still runs after unregister")

    bpy.ops.preferences.addon_enable(module=MODULE)
    assert all(_registered().values()), _registered()
    _build_default_scene()
