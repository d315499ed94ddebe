"""A real full disk for tests (issue 39.8): a tmpfs of a few hundred KB, filled to the last page,
mounted in a private mount namespace of a child process (`unshare --mount`), so it disappears with
the child however the test ends and no other process sees it. The command under test runs inside,
and the child reports every file left on the disk (name, size, sha256, and the bytes of small ones).

Needs root (CAP_SYS_ADMIN) and util-linux's `unshare`; `full_disk_unavailable()` says why not."""

from __future__ import annotations

import base64
import functools
import json
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

_CHILD = textwrap.dedent(
    """
    import base64, hashlib, json, os, subprocess, sys
    disk, size_kb, setup, command, timeout = json.loads(sys.argv[1])
    subprocess.run(["mount", "-t", "tmpfs", "-o", f"size={size_kb}k,mode=0755", "tmpfs", disk], check=True)
    for name, data in setup.items():
        path = os.path.join(disk, name)
        os.makedirs(os.path.dirname(path), exist_ok=True)
        with open(path, "wb") as f:
            f.write(base64.b64decode(data))
    free_before = os.statvfs(disk).f_bavail
    with open(os.path.join(disk, "filler"), "wb", buffering=0) as f:  # fill to the last page
        try:
            while True:
                f.write(b"\\0" * 4096)
        except OSError:
            pass
    done = subprocess.run([c.replace("{disk}", disk) for c in command], capture_output=True, text=True,
                          timeout=timeout)
    files = {}
    for root, _, names in os.walk(disk):
        for name in names:
            path = os.path.join(root, name)
            data = open(path, "rb").read() if name != "filler" else b""
            files[os.path.relpath(path, disk)] = {
                "size": os.path.getsize(path), "sha256": hashlib.sha256(data).hexdigest(),
                "data": base64.b64encode(data).decode() if len(data) < 65536 else None,
            }
    print(json.dumps({"code": done.returncode, "stdout": done.stdout, "stderr": done.stderr,
                      "files": files, "free_pages_before_filling": free_before}))
    """
)


@functools.cache
def full_disk_unavailable() -> str | None:
    """None where a tmpfs can be mounted in a private namespace, else why not (for pytest.skip)."""
    if shutil.which("unshare") is None:
        return "no `unshare` (util-linux) to make a private mount namespace"
    probe = subprocess.run(
        ["unshare", "--mount", "--propagation", "private", "mount", "-t", "tmpfs", "-o", "size=64k", "tmpfs", "/mnt"],
        capture_output=True,
        text=True,
    )
    if probe.returncode != 0:
        return f"cannot mount a tmpfs here (needs root or CAP_SYS_ADMIN): {probe.stderr.strip()}"
    return None


def run_on_full_disk(
    mount_point: Path, command: list[str], setup: dict[str, bytes], size_kb: int = 256, timeout: float = 300
) -> dict:
    """Mounts a `size_kb` tmpfs at `mount_point` (an empty folder) in a private namespace, writes
    the `setup` files (relative names), fills the rest, runs `command` ("{disk}" in an argument
    becomes the mount point) and returns {"code", "stdout", "stderr", "files": {name: {"size",
    "sha256", "data" (bytes or None)}}} with the filler left out."""
    mount_point.mkdir(parents=True, exist_ok=True)
    spec = [str(mount_point), size_kb, {k: base64.b64encode(v).decode() for k, v in setup.items()}, command, timeout]
    done = subprocess.run(
        ["unshare", "--mount", "--propagation", "private", sys.executable, "-c", _CHILD, json.dumps(spec)],
        capture_output=True,
        text=True,
        timeout=timeout + 60,
    )
    assert done.returncode == 0, f"full-disk child failed:\n{done.stdout[-3000:]}\n{done.stderr[-3000:]}"
    result = json.loads(done.stdout)
    for entry in result["files"].values():
        entry["data"] = None if entry["data"] is None else base64.b64decode(entry["data"])
    result["files"].pop("filler")
    return result
