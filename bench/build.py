"""Build and CPU-traversal benchmark against Embree, measured in the same run.

    python bench/build.py [--sizes 250000,1000000] [--threads 1,2] [--repeat 3]

For each scene (a detailed model in a large room, where median splits go wrong; and uniformly
random small triangles) and each split method: build ms, Mprims/s, nodes, height, SAH cost, and
closest-hit Mrays/s for coherent camera rays and random rays (binary tree with a stack,
stackless, and the 4-wide copy); Embree's build (the
commit, default quality) and rtcIntersect1 trace beside them, with ratios. Each thread count runs
in its own process pinned to that many cores. Writes bench/results/build.json.
"""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _common  # noqa: E402

CONFIGS = [  # (label, build kwargs)
    ("median", dict(method="median")),
    ("mean", dict(method="mean")),
    ("midpoint", dict(method="midpoint")),
    ("lbvh", dict(method="lbvh")),
    ("sah12", dict(method="sah", bins=12)),
    ("sah32", dict(method="sah", bins=32)),
    ("sah12 leaf<=4", dict(method="sah", bins=12, max_leaf_size=4)),
    ("sah12 best-axis", dict(method="sah", bins=12, axis="best")),
    ("sweep_sah", dict(method="sweep_sah")),
]


def scenes(sizes):
    from bvhlab.library import procedural

    for n in sizes:
        yield f"room {n // 1000}k", procedural.model_in_room(n)
        yield f"uniform {n // 1000}k", procedural.random_triangles(n, size=1.0 / n ** (1 / 3), seed=1)


def measure(threads: int, sizes: list[int], repeat: int) -> dict:
    """One process, pinned to `threads` cores."""
    _common.pin_to_cores(threads)
    import bvhlab
    from bvhlab.library import procedural

    out = {"threads": threads, "scenes": []}
    for name, tris in scenes(sizes):
        n = len(tris)
        cam = procedural.camera_rays(tris, 640, 480)
        rnd = procedural.random_rays(tris, 200_000, seed=3)
        emb = _common.Embree(tris)
        emb_build = _common.statistics.median(emb.build() for _ in range(repeat))
        emb_cam, _ = _common.median_time(lambda: emb.trace(*cam), repeat)
        emb_rnd, _ = _common.median_time(lambda: emb.trace(*rnd), repeat)
        scene = {"name": name, "triangles": n, "embree": {
            "build_ms": emb_build * 1e3, "mprims_s": n / emb_build / 1e6,
            "camera_mrays_s": len(cam[0]) / emb_cam / 1e6, "random_mrays_s": len(rnd[0]) / emb_rnd / 1e6}, "methods": []}
        for label, kwargs in CONFIGS:
            reps = 1 if kwargs["method"] == "sweep_sah" else repeat
            t, bvh = _common.median_time(lambda: bvhlab.build(tris, threads=threads, **kwargs), reps)
            s = bvh.stats
            row = {"label": label, **kwargs, "build_ms": t * 1e3, "mprims_s": n / t / 1e6,
                   "nodes": s["nodes"], "height": s["height"], "sah_cost": s["sah_cost"]}
            for rays_name, rays in (("camera", cam), ("random", rnd)):
                for trav in ("stack", "stackless", "wide"):
                    bvh.intersect(rays[0][:1], rays[1][:1], traversal=trav)  # the wide copy is made on first use
                    tt, _ = _common.median_time(lambda: bvh.intersect(*rays, traversal=trav, threads=threads), repeat)
                    row[f"{rays_name}_{trav}_mrays_s"] = len(rays[0]) / tt / 1e6
            scene["methods"].append(row)
            print(f"  [{threads}t] {name} {label}: {row['build_ms']:.0f} ms", file=sys.stderr, flush=True)
        out["scenes"].append(scene)
    return out


def report(result: dict) -> str:
    texts = []
    for sc in result["scenes"]:
        e = sc["embree"]
        rows = []
        for m in sc["methods"]:
            rows.append([m["label"], m["build_ms"], m["mprims_s"], m["mprims_s"] / e["mprims_s"], m["nodes"],
                         m["height"], m["sah_cost"], m["camera_wide_mrays_s"],
                         m["camera_wide_mrays_s"] / e["camera_mrays_s"], m["random_stack_mrays_s"],
                         m["random_stackless_mrays_s"], m["random_wide_mrays_s"],
                         m["random_wide_mrays_s"] / e["random_mrays_s"]])
        rows.append(["Embree (default)", e["build_ms"], e["mprims_s"], 1.0, "", "", "", e["camera_mrays_s"], 1.0,
                     "", "", e["random_mrays_s"], 1.0])
        texts.append(_common.print_table(
            ["method", "build ms", "Mprims/s", "x Embree", "nodes", "height", "SAH", "cam wide Mrays/s", "x Embree",
             "rnd stack", "rnd stackless", "rnd wide", "x Embree"],
            rows, title=f"\n{sc['name']} ({sc['triangles']} triangles), {result['threads']} thread(s)"))
    return "\n".join(texts)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--sizes", default="250000,1000000")
    ap.add_argument("--threads", default="1,2")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--child", type=int, help=argparse.SUPPRESS)
    args = ap.parse_args()
    sizes = [int(s) for s in args.sizes.split(",")]
    if args.child:
        print(json.dumps(measure(args.child, sizes, args.repeat)))
        return
    results = {"machine": _common.machine(), "runs": []}
    for threads in (int(t) for t in args.threads.split(",")):
        r = _common.run_child(__file__, ["--child", str(threads), "--sizes", args.sizes, "--repeat", str(args.repeat)])
        results["runs"].append(r)
        report(r)
    path = _common.write_json("build.json", results)
    print(f"\nwrote {path}")


if __name__ == "__main__":
    main()
