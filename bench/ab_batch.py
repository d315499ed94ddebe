"""An A/B run of two bvh_bench binaries (helper trav11's, design.md "Packets for coherent rays"):
bvh_bench trace of the old binary and the new one alternately on each scene's primary (and random)
rays, pinned to one core, every round Embree 3 MEDIUM, tinybvh 1.9 BVH8_CPU and bvhlab's batch (and
single-ray) rows in one process; writes --json NAME (bench/results/trav11_ab.json by default).

    .venv/bin/python bench/ab_batch.py OLD_BVH_BENCH NEW_BVH_BENCH [--scenes ...]
        [--sets primary,random] [--rounds 3] [--repeat 3]
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _common  # noqa: E402
import _peers  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("old")
    ap.add_argument("new")
    ap.add_argument("--scenes", default="sponza,room1m,repeat1m,vast1m")
    ap.add_argument("--sets", default="primary,random")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--json", default="trav11_ab.json")
    args = ap.parse_args()
    _common.json_path(args.json)  # a bad folder fails now, not after the run
    machine = _common.machine()
    print(_common.machine_line(machine), file=sys.stderr, flush=True)
    peers = ["embree:medium", "tinybvh:", "bvhlab:", "bvhlab:batch=1"]
    runs: dict = {}
    with tempfile.TemporaryDirectory() as tmp:
        for scene, tris in _peers.scenes(args.scenes.split(",")).items():
            mesh, rays = _peers.write_inputs(Path(tmp), scene, tris)
            for name in args.sets.split(","):
                key = f"{scene} {name}"
                runs[key] = {"old": [], "new": []}
                for r in range(args.rounds):
                    for label in ("old", "new"):
                        exe = Path(getattr(args, label))
                        cmd = ["trace", str(mesh), *_peers.ray_args(name, rays[name])]
                        for p in peers:
                            cmd += ["--peer", p]
                        out = _peers.run(exe, cmd + ["--repeat", str(args.repeat)], 1)
                        ray_set = out["ray_sets"][0]
                        rows = {p["spec"]: min(p["cpu_seconds"]) for p in ray_set["peers"]}
                        rows["hits"] = {p["spec"]: p["hits"] for p in ray_set["peers"]}
                        runs[key][label].append(rows)
                        best = min(rows["embree:medium"], rows["tinybvh:"])
                        print(
                            f"{key:18} round {r} {label}: batch / best {best / rows['bvhlab:batch=1']:.3f}  "
                            f"single / best {best / rows['bvhlab:']:.3f}",
                            flush=True,
                        )
    result = {"what": __doc__.splitlines()[0], "machine": machine, "runs": runs}
    print(f"wrote {_common.write_json(args.json, result)}")


if __name__ == "__main__":
    main()
