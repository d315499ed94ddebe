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
