"""Every Blender check of bvhlab, for a real Blender binary or for Python with bpy as a module:

    blender --background --factory-startup --python-exit-code 1 --python tests/blender/run.py
    .venv/bin/python tests/blender/run.py [--only GROUP|GROUP/NAME ...] [--zip dist/bvhlab-0.1.0.zip]

Groups: install (the built zip installs, unregisters cleanly, enables again), export (bundled and
small scenes), addon (operators), instancing (Build and F12 on geometry-nodes and nested
collection instances), engine (the render engine: passes against the CPU reference,
re-renders, animation, `blender -b ... -a` under a binary, the viewport's camera and worker),
cameras (every camera kind and setting: the engine's Depth pass against Cycles', F12 on each
backend and the viewport's camera; depth of field, a huge F12, Esc under a binary), no_vulkan
(backend "vulkan" without a driver), gpu (overlay drawn into a GPUOffScreen; batch time for a
million boxes). Under a Blender binary the add-on (and with it the bvhlab wheel) comes from the
zip, so `make addon` first; under Python, from addon/ in place unless the install group ran. The
checks are listed once, in tests/blender/registry.py; pytest runs each of them as a test of its
own (tests/python/test_blender_checks.py). Blender binaries re-run themselves with BLENDER_USER_RESOURCES set to a
temporary folder, so nothing is written to the user's Blender configuration.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
import traceback
from pathlib import Path

IN_BLENDER = "bpy" in sys.modules  # a Blender binary imports bpy before running scripts
sys.path.insert(0, str(Path(__file__).resolve().parent))

import registry  # noqa: E402


def _arguments():
    argv = sys.argv[sys.argv.index("--") + 1 :] if "--" in sys.argv else ([] if IN_BLENDER else sys.argv[1:])
    ap = argparse.ArgumentParser(
        prog="run.py", description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    ap.add_argument(
        "--only", nargs="+", metavar="GROUP[/NAME]", help=f"groups ({', '.join(registry.GROUPS)}) or checks"
    )
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


def main() -> int:
    args = _arguments()
    if IN_BLENDER and "BLENDER_USER_RESOURCES" not in os.environ:
        return _rerun_with_private_user_folder()
    import platform

    import harness  # sets up the user folder before bpy starts, under Python

    only = set(args.only or ())
    unknown = {o for o in only if o.split("/")[0] not in registry.GROUPS}
    if unknown:
        raise SystemExit(f"run.py: no group {sorted(unknown)}; the groups are {registry.GROUPS}")
    every = registry.GROUPS if IN_BLENDER or args.zip else tuple(g for g in registry.GROUPS if g != "install")
    groups = {o.split("/")[0] for o in only} or set(every)
    if IN_BLENDER:
        groups.add("install")  # the only way a Blender binary gets bvhlab
    zip_path = args.zip or _default_zip()
    print(f"Blender {harness.bpy.app.version_string}, Python {platform.python_version()}", flush=True)
    failures, listed = [], set()
    with tempfile.TemporaryDirectory() as tmp:
        for group in (g for g in registry.GROUPS if g in groups):
            if group in registry.ADDON_GROUPS and harness._addon_module is None:
                harness.enable_addon_from_source()
            for check in registry.checks([group]):
                if only and group not in only and check.id not in only:
                    continue
                listed.add(check.id)
                reason = check.skip_reason(binary=IN_BLENDER)
                if reason:
                    print(f"SKIP {check.id} ({reason})", flush=True)
                    continue
                start = time.perf_counter()
                try:
                    check.run(Path(tmp) / check.id, zip_path)
                    print(f"PASS {check.id} ({time.perf_counter() - start:.1f} s)", flush=True)
                except Exception:
                    traceback.print_exc(file=sys.stdout)  # after the check's own output, before its FAIL
                    failures.append(check.id)
                    print(f"FAIL {check.id}", flush=True)
    failures += [f"{name} (no such check)" for name in sorted(only - groups - listed)]
    print(f"{len(failures)} failed" + (": " + "; ".join(failures) if failures else ""), flush=True)
    return 1 if failures else 0


if __name__ == "__main__":
    code = main()
    if IN_BLENDER and code:
        raise SystemExit(code)  # with --python-exit-code 1, Blender exits non-zero
    if not IN_BLENDER:
        import harness

        harness.exit_without_teardown(code)  # every check has run and reported
