"""Every Blender check of bvhlab, for a real Blender binary or for Python with bpy as a module:

    blender --background --factory-startup --python-exit-code 1 --python tests/blender/run.py
    .venv/bin/python tests/blender/run.py [--only GROUP ...] [--zip dist/bvhlab-0.1.0.zip]

Groups: install (the built zip installs, unregisters cleanly, enables again), export (bundled and
small scenes), addon (operators), instancing (Build and F12 on geometry-nodes and nested
collection instances), engine (the render engine: passes against the CPU reference,
re-renders, animation, `blender -b ... -a` under a binary, the viewport's camera and worker),
cameras (every camera kind and setting: the engine's Depth pass against Cycles', F12 on each
backend and the viewport's camera; depth of field, a huge F12, Esc under a binary), no_vulkan
(backend "vulkan" without a driver), gpu (overlay drawn into a GPUOffScreen; batch time for a
million boxes). Under a Blender binary the add-on (and with it the bvhlab wheel) comes from the
zip, so `make addon` first; under Python, from addon/ in place unless the install group ran. The
checks are the ones pytest runs (tests/python/test_blender_*.py, test_addon*.py, test_engine.py,
test_cameras.py). Blender binaries re-run themselves with BLENDER_USER_RESOURCES set to a
temporary folder, so nothing is written to the user's Blender configuration.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import traceback
from pathlib import Path

IN_BLENDER = "bpy" in sys.modules  # a Blender binary imports bpy before running scripts
sys.path.insert(0, str(Path(__file__).resolve().parent))

GROUPS = ("install", "export", "addon", "instancing", "engine", "cameras", "no_vulkan", "gpu")


def _arguments():
    argv = sys.argv[sys.argv.index("--") + 1 :] if "--" in sys.argv else ([] if IN_BLENDER else sys.argv[1:])
    ap = argparse.ArgumentParser(
        prog="run.py", description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    ap.add_argument("--only", nargs="+", choices=GROUPS, default=None)
    ap.add_argument("--zip", type=Path, default=None, help="extension zip (default: the one in dist/)")
    return ap.parse_args(argv)


def _rerun_with_private_user_folder() -> int:
    import bpy

    env = dict(os.environ, BLENDER_USER_RESOURCES=tempfile.mkdtemp(prefix="bvhlab_blender_user_"))
    command = [
        bpy.app.binary_path,
        "--background",
        "--factory-startup",
        "--python-exit-code",
        "1",
        "--python",
        __file__,
        "--",
        *(sys.argv[sys.argv.index("--") + 1 :] if "--" in sys.argv else []),
    ]
    return subprocess.run(command, env=env).returncode


def _default_zip() -> Path:
    import tomllib

    import harness

    version = tomllib.loads((harness.ADDON_DIR / "blender_manifest.toml").read_text())["version"]
    return harness.ROOT / "dist" / f"bvhlab-{version}.zip"


def _checks(groups, zip_path: Path, tmp: Path):
    """(group, name, callable) in run order; modules are imported late: under a Blender binary
    bvhlab is importable only once the zip is installed."""
    import harness

    if "install" in groups:
        import platform

        import checks_install
        import checks_versions

        if sys.version_info >= (3, 12):  # where a stable-ABI wheel could load
            yield (
                "install",
                "abi3_beside_cp311_refused",
                lambda: checks_versions.check_abi3_beside_cp311_refused(zip_path),
            )
        yield "install", "install_enable_disable", lambda: checks_install.check_install_enable_disable(zip_path)
        blender = f"Blender {harness.bpy.app.version_string}, Python {platform.python_version()}"
        yield (
            "install",
            f"installed_core_is_this_pythons ({blender})",
            checks_versions.check_installed_core_is_this_pythons,
        )
    if "export" in groups:
        import checks_bundled
        import checks_cases

        for name in harness.scenes_index():
            yield "export", f"bundled {name}", lambda name=name: checks_bundled.check_bundled_scene(name)
        for check in checks_cases.CASE_CHECKS:
            yield "export", check.__name__, check
        yield "export", "scene_file_round_trip", lambda: checks_cases.check_scene_file_round_trip(tmp)
        yield "export", "large_export", checks_bundled.check_large_export
    if groups & {"addon", "instancing", "engine", "cameras", "no_vulkan", "gpu"} and harness._addon_module is None:
        harness.enable_addon_from_source()
    if "addon" in groups:
        import checks_addon

        for name, variants in checks_addon.BUILD_SCENES.items():
            yield (
                "addon",
                f"build_matches_direct {name}",
                lambda n=name, v=variants: checks_addon.check_build_matches_direct(n, v),
            )
        for check in (
            checks_addon.check_overlay_ranges,
            checks_addon.check_build_shows_overlay,
            checks_addon.check_bad_input_reports,
            checks_addon.check_render,
            checks_addon.check_render_without_light,
        ):
            yield "addon", check.__name__, check
        yield "addon", "export_stats", lambda: checks_addon.check_export_stats(tmp)
        yield "addon", "compare", lambda: checks_addon.check_compare(tmp)
        import checks_settings_path

        for check in checks_settings_path.SETTINGS_PATH_CHECKS:
            yield "addon", check.__name__, lambda c=check: _in_own_folder(c, tmp / c.__name__)
        yield "addon", "path_properties", lambda: checks_addon.check_path_properties(tmp)
        yield "addon", "engine_panels", lambda: checks_addon.check_engine_panels_follow_the_renders(tmp)
    if "instancing" in groups:
        import checks_instancing

        for check in checks_instancing.INSTANCING_CHECKS:
            yield "instancing", check.__name__, lambda c=check: _in_own_folder(c, tmp / c.__name__)
    if "engine" in groups:
        import checks_engine

        for check in checks_engine.engine_checks(binary=IN_BLENDER):
            yield "engine", check.__name__, lambda c=check: _in_own_folder(c, tmp / c.__name__)
    if "cameras" in groups:
        import checks_cameras
        import checks_final

        backends = checks_cameras.vulkan_backends()
        for name in checks_cameras.SETTINGS:
            yield (
                "cameras",
                f"{name} against Cycles",
                lambda n=name: checks_cameras.check_settings_against_cycles(tmp / "cameras", backends, names=[n]),
            )
        for check in checks_final.final_checks(binary=IN_BLENDER):
            yield "cameras", check.__name__, lambda c=check: _in_own_folder(c, tmp / c.__name__)
    if "no_vulkan" in groups:
        import checks_addon

        # Read when the first Vulkan instance is made, which no earlier check does (they use the CPU).
        os.environ["VK_DRIVER_FILES"] = os.environ["VK_ICD_FILENAMES"] = "/nonexistent/bvhlab_icd.json"
        yield "no_vulkan", "no_vulkan_reported", checks_addon.check_no_vulkan_reported
    if "gpu" in groups:
        import checks_gpu

        yield "gpu", "overlay_pixels", checks_gpu.check_overlay_pixels
        yield "gpu", "overlay_colour_by_depth", checks_gpu.check_overlay_colour_by_depth
        yield "gpu", "overlay_million_boxes", checks_gpu.check_overlay_million_boxes


def _in_own_folder(check, folder: Path):
    """Run a check, handing it an empty folder of its own when it takes one."""
    if not check.__code__.co_argcount:
        return check()
    folder.mkdir(parents=True, exist_ok=True)
    return check(folder)


def main() -> int:
    args = _arguments()
    if IN_BLENDER and "BLENDER_USER_RESOURCES" not in os.environ:
        return _rerun_with_private_user_folder()
    import harness  # noqa: F401  (sets up the user folder before bpy starts, under Python)

    groups = set(args.only or (GROUPS if IN_BLENDER or args.zip else set(GROUPS) - {"install"}))
    if IN_BLENDER:
        groups.add("install")  # the only way a Blender binary gets bvhlab
    failures = []
    with tempfile.TemporaryDirectory() as tmp:
        for group, name, check in _checks(groups, args.zip or _default_zip(), Path(tmp)):
            try:
                check()
                print(f"PASS {group}: {name}", flush=True)
            except Exception:
                traceback.print_exc()
                failures.append(f"{group}: {name}")
                print(f"FAIL {group}: {name}", flush=True)
    print(f"{len(failures)} failed" + (": " + "; ".join(failures) if failures else ""), flush=True)
    return 1 if failures else 0


if __name__ == "__main__":
    code = main()
    if IN_BLENDER and code:
        raise SystemExit(code)  # with --python-exit-code 1, Blender exits non-zero
    if not IN_BLENDER:
        # bpy 4.2 as a module segfaults while the interpreter shuts down once any Panel class
        # has been registered (SpaceType's destructor frees the class after the interpreter is
        # gone: a five-line script registering one Panel does it) or a shader made with
        # gpu.shader.create_from_info has existed. Blender's teardown, not bvhlab's code. Every
        # check has run and reported: skip the teardown.
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(code)
