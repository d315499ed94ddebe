"""The built extension zip installs and enables headless, unregisters cleanly, and enables again.
Run in a process of its own with BLENDER_USER_RESOURCES pointing at a temporary folder
(tests/blender/run.py --only install --zip dist/bvhlab-<version>.zip)."""

from __future__ import annotations

import importlib.util
import json
import re
import sys
import tempfile
import zipfile
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


def _build_script():
    """scripts/build_addon.py, which labels the zip's wheels (relabel_wheel, wheel_digests)."""
    spec = importlib.util.spec_from_file_location("bvhlab_build_addon", harness.ROOT / "scripts" / "build_addon.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _another_build(zip_path: Path, out: Path, tag: str) -> tuple[Path, str]:
    """The zip as a rebuild of the same version with another core would be: this Python's wheel
    with one more file in its package, labelled with its new digest as `make addon` labels it, and
    the manifest and the digests naming it. Returns the zip and the new package's digest."""
    build = _build_script()
    with zipfile.ZipFile(zip_path) as source:
        names = source.namelist()
        old = next(n for n in names if re.search(rf"-{tag}-{tag}-[^/]*\.whl$", n))
        changed = out / Path(old).name
        with zipfile.ZipFile(source.open(old)) as wheel, zipfile.ZipFile(changed, "w") as rebuilt:
            for info in wheel.infolist():
                rebuilt.writestr(info, wheel.read(info))
            rebuilt.writestr("bvhlab/rebuilt_marker.txt", "another build of the same version")
        digest = build.wheel_digests([changed])[tag]
        (out / "wheels").mkdir()
        new = build.relabel_wheel(changed, out / "wheels", build.core_check.wheel_label(digest))
        new_name = f"wheels/{new.name}"
        probe = out / "bvhlab_rebuilt.zip"
        with zipfile.ZipFile(probe, "w") as target:
            for name in names:
                data = source.read(name)
                if name == old:
                    name, data = new_name, new.read_bytes()
                elif name == "blender_manifest.toml":
                    data = data.replace(old.encode(), new_name.encode())
                elif name == build.core_check.DIGESTS:
                    data = json.dumps(dict(json.loads(data), **{tag: digest})).encode()
                target.writestr(name, data)
    return probe, digest


def _install(zip_path: Path) -> None:
    result = bpy.ops.extensions.package_install_files(
        filepath=str(zip_path), repo="user_default", enable_on_install=True
    )
    assert result == {"FINISHED"}, result


def check_installed_over_while_running(zip_path: Path) -> None:
    """Under a Blender binary, after the zip's install. A rebuild of the same version installed
    while Blender runs (the probe's upgrade) replaces the core's files, as its wheel's version
    carries its package's digest, and the panel asks for a restart, as the core loaded is the one
    before; the first zip installed again leaves no warning. (Before the label, Blender kept the
    old wheel, and the new add-on ran on the old core, also after a restart.)"""
    import bvhlab

    site = Path(bpy.utils.user_resource("EXTENSIONS", path=".local"))
    installed = Path(bvhlab.__file__).resolve().parent
    assert installed.is_relative_to(site.resolve()), f"bvhlab loaded from {installed}, not from the zip's wheel"
    package = sys.modules[MODULE]
    check = sys.modules[f"{MODULE}.core_check"]
    assert package.state.core_warning == "", package.state.core_warning
    loaded = check.package_digest(check.installed_files(installed))
    with tempfile.TemporaryDirectory() as tmp:
        rebuilt, digest = _another_build(zip_path, Path(tmp), check.python_tag())
        assert digest != loaded
        _install(rebuilt)
        package = sys.modules[MODULE]  # the add-on's modules were imported again
        assert package.state.core_warning == check.RESTART, package.state.core_warning
        assert (installed / "rebuilt_marker.txt").is_file(), "Blender kept the wheel installed before"
        assert check.package_digest(check.installed_files(installed)) == digest
        infos = sorted(p.name for p in site.rglob("bvhlab-*.dist-info"))
        assert len(infos) == 1 and digest[: check.LABEL_DIGITS] in infos[0], infos
    _install(zip_path)
    package = sys.modules[MODULE]
    assert package.state.core_warning == "", package.state.core_warning
    assert not (installed / "rebuilt_marker.txt").exists()
    assert check.package_digest(check.installed_files(installed)) == loaded
