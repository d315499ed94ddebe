"""Build benchmark: bvhlab's builders beside Embree 3 (C++, LOW/MEDIUM/HIGH), Embree 4 (embreex)
and tinybvh (Build: its AVX2 builder; BuildHQ: its SBVH; Build + Optimize: its reinsertion; when a
local copy is given), measured in the same run.

    python bench/build.py [--scenes sponza,room1m,uniform1m] [--threads 1,2] [--repeat 5]
                          [--rounds 2] [--callgrind sponza] [--tinybvh DIR]

All C++ builders run inside one bvh_bench process per (scene, thread count), pinned to that many
cores, interleaved (each repetition builds with every system in turn); a round runs one such
process per thread count, then embreex's, and `--rounds` rounds follow each other, so the thread
counts alternate too. Prints, per scene, build ms and Mprims/s (medians of all builds) with ratios
against Embree MEDIUM and tinybvh, scaling on the most threads (the median of the rounds' ratios,
each round's 1T median over its own), how many cores were busy there (CPU time of all threads over
wall time) and the page faults of one build there, SAH cost (bvhlab's convention), references per
primitive (leaf slots: above 1 with spatial splits) and callgrind instructions per primitive, and
writes bench/results/build.json.
tinybvh is never part of bvhlab: pass the folder of a local copy of github.com/jbikker/tinybvh
(or set BVHLAB_TINYBVH_DIR).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _common  # noqa: E402
import _peers  # noqa: E402

PEERS = [  # (label, bvh_bench spec)
    ("bvhlab sah (defaults)", "bvhlab:"),
    ("bvhlab sah12, largest, leaf 1 (report)", "bvhlab:method=sah,bins=12,axis=largest,leaf=1,span=centroids,block=1"),
    ("bvhlab median", "bvhlab:method=median"),
    ("bvhlab mean", "bvhlab:method=mean"),
    ("bvhlab midpoint", "bvhlab:method=midpoint"),
    ("bvhlab lbvh", "bvhlab:method=lbvh"),
    ("bvhlab sbvh (spatial splits)", "bvhlab:method=sbvh"),
    ("Embree 3 LOW", "embree:low"),
    ("Embree 3 MEDIUM", "embree:medium"),
    ("Embree 3 HIGH", "embree:high"),
    ("tinybvh Build", "tinybvh:"),
    ("tinybvh BuildHQ (SBVH)", "tinybvh:hq"),
    ("tinybvh Build + Optimize (25 iterations)", "tinybvh:opt"),
]


def measure_scene(exe: Path, path: Path, tris, threads: list[int], repeat: int, rounds: int, peers: list) -> dict:
    """Every peer's build times per thread count (all rounds), SAH and nodes; embreex's commits."""
    args = ["build", str(path)] + [a for _, spec in peers for a in ("--peer", spec)] + ["--repeat", str(repeat)]
    rows = {spec: {"label": label, "spec": spec, "seconds": {}} for label, spec in peers}
    embreex, warm_up = {}, {}
    for _ in range(rounds):  # thread counts alternate: a slow stretch of the machine hits all of them
        for t in threads:
            run = _peers.run(exe, args, t)
            warm_up.setdefault(str(t), []).append(run["warm_up_rounds"])
            for p in run["peers"]:
                row = rows[p["spec"]]
                row["seconds"].setdefault(str(t), []).extend(p["seconds"])
                row.setdefault("round_medians", {}).setdefault(str(t), []).append(_peers.median(p["seconds"]))
                row.setdefault("cpu_seconds", {}).setdefault(str(t), []).extend(p["cpu_seconds"])
                row.setdefault("page_faults", {}).setdefault(str(t), []).extend(p["page_faults"])
                row["sah"], row["nodes"], row["references"] = p["sah"], p["nodes"], p.get("references")
            child = _common.run_child(__file__, ["--embreex-child", str(path), "--repeat", str(repeat)], cores=t)
            if child.get("seconds"):
                embreex.setdefault(str(t), []).extend(child["seconds"])
    return {"triangles": len(tris), "peers": list(rows.values()), "embreex": embreex, "warm_up_rounds": warm_up}


def count_instructions(exe: Path, path: Path, result: dict) -> None:
    for row in result["peers"]:
        n = _peers.instructions(exe, [str(path), "--peer", row["spec"]])
        row["instructions"] = n
        print(f"  callgrind {row['label']}: {n}", file=sys.stderr, flush=True)


def report(name: str, r: dict, threads: list[int]) -> str:
    n = r["triangles"]

    def ms(row, t):
        return _peers.median(row["seconds"][str(t)]) * 1e3 if str(t) in row["seconds"] else float("nan")

    def scaling(row, t):  # per round, 1T against t threads measured next to it
        if "1" not in row["round_medians"]:
            return float("nan")
        rounds = zip(row["round_medians"]["1"], row["round_medians"][str(t)])
        return _peers.median([one / many for one, many in rounds])

    by_spec = {row["spec"]: row for row in r["peers"]}
    medium, tiny = by_spec.get("embree:medium"), by_spec.get("tinybvh:")
    rows = []
    for row in r["peers"]:
        cells = [row["label"]]
        for t in threads:
            cells += [ms(row, t), n / ms(row, t) / 1e3]
        cells += [ms(medium, 1) / ms(row, 1) if medium else "", ms(tiny, 1) / ms(row, 1) if tiny else ""]
        cells += [scaling(row, threads[-1]) if len(threads) > 1 else ""]
        last = str(threads[-1])
        cpu, wall, faults = row["cpu_seconds"][last], row["seconds"][last], row["page_faults"][last]
        cells += [sum(cpu) / sum(wall), round(_peers.median(faults))]
        ins = row.get("instructions")
        refs = row.get("references")
        cells += [row["sah"] if row["sah"] is not None else "", row["nodes"], refs / n if refs else ""]
        cells += [round(ins / n) if ins else ""]
        rows.append(cells)
    for t in threads:
        if str(t) in r["embreex"]:
            e = _peers.median(r["embreex"][str(t)]) * 1e3
            rows.append([f"embreex (Embree 4) commit, {t}T", e, n / e / 1e3] + [""] * (2 * len(threads) + 7))
    headers = ["builder"] + [h for t in threads for h in (f"ms {t}T", f"Mprims/s {t}T")]
    headers += ["x MEDIUM 1T", "x tinybvh 1T", f"{threads[-1]}T/1T", f"cores busy {threads[-1]}T"]
    headers += [f"faults {threads[-1]}T", "SAH", "nodes", "refs/prim", "instr/prim"]
    return _common.print_table(headers, rows, title=f"\n{name}: {n} triangles")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scenes", default="sponza,room1m,uniform1m")
    ap.add_argument("--threads", default="1,2")
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--rounds", type=int, default=2)
    ap.add_argument("--callgrind", default="sponza", help="scenes whose builds callgrind counts ('' for none)")
    ap.add_argument("--tinybvh", default=os.environ.get("BVHLAB_TINYBVH_DIR"))
    ap.add_argument("--peers", help="comma-separated bvh_bench specs to keep (default: all; _peers.split_specs)")
    ap.add_argument("--json", default="build.json", help="results file name in bench/results (or a path)")
    ap.add_argument("--embreex-child", help=argparse.SUPPRESS)
    args = ap.parse_args()
    _common.json_path(args.json)  # a bad folder fails now, not after the run
    if args.embreex_child:
        import numpy as np

        tris = np.fromfile(args.embreex_child, np.float32).reshape(-1, 3, 3)
        print(json.dumps({"seconds": _peers.embreex_commit_seconds(tris, args.repeat)}))
        return
    exe = _peers.build_bvh_bench(args.tinybvh)
    threads = [int(t) for t in args.threads.split(",")]
    peers = [(label, spec) for label, spec in PEERS if args.tinybvh or not spec.startswith("tinybvh")]
    if args.peers:
        peers = _peers.chosen_rows(args.peers, peers, args.tinybvh)
    results = {"machine": _common.machine(), "threads": threads, "scenes": {}}
    print(_common.machine_line(results["machine"]), file=sys.stderr, flush=True)
    with tempfile.TemporaryDirectory() as tmp:
        for name, tris in _peers.scenes(args.scenes.split(",")).items():
            path = Path(tmp) / f"{name}.f32"
            tris.tofile(path)
            print(f"{name}: timing", file=sys.stderr, flush=True)
            r = measure_scene(exe, path, tris, threads, args.repeat, args.rounds, peers)
            if name in args.callgrind.split(","):
                count_instructions(exe, path, r)
            results["scenes"][name] = r
            report(name, r, threads)
    print(f"\nwrote {_common.write_json(args.json, results)}")


if __name__ == "__main__":
    main()
