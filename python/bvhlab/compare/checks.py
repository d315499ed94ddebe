"""The report's claims (§4.2, §5.2), tested on our numbers: each is printed as holding or not —
the data are never bent to fit."""
from __future__ import annotations


def _row(rows, method):
    return next((r for r in rows if r["method"] == method), None)


def report_checks(rows: list[dict], uniform_rows: list[dict] | None = None) -> list[dict]:
    out = []

    def claim(text, holds, detail):
        out.append({"claim": text, "holds": bool(holds), "detail": detail})

    by_frame = sorted(rows, key=lambda r: r["frame_ms"])
    sah_rows = [r for r in rows if r["method"].startswith("sah") or r["method"] == "sweep_sah"]
    if sah_rows:
        best = by_frame[0]
        claim("SAH has the lowest frame time", best in sah_rows,
              f"fastest: {best['method']} {best['frame_ms']:.1f} ms")
    median, mean = _row(rows, "median"), _row(rows, "mean")
    if median and mean:
        ratio = mean["frame_ms"] / median["frame_ms"]
        claim("mean is clearly faster than median (at least 10% less frame time)", ratio <= 0.9,
              f"mean/median frame time = {ratio:.2f} (report: {30.1 / 41.8:.2f})")
    if mean and sah_rows:
        best_sah = min(sah_rows, key=lambda r: r["frame_ms"])
        ratio = mean["frame_ms"] / best_sah["frame_ms"]
        claim("mean comes close to SAH (within 25% of its frame time)", ratio <= 1.25,
              f"mean/{best_sah['method']} frame time = {ratio:.2f} (report: {30.1 / 26.1:.2f})")
    if median:
        lowest = min(r["height"] for r in rows)
        claim("median gives the lowest tree", median["height"] == lowest,
              "heights: " + ", ".join(f"{r['method']} {r['height']}" for r in rows))
    sah12, sah32 = _row(rows, "sah12"), _row(rows, "sah32")
    if sah12 and sah32:
        claim("32 bins instead of 12 change the frame time little (within 5%) but cost more build time",
              abs(sah32["frame_ms"] / sah12["frame_ms"] - 1) <= 0.05 and sah32["build_ms"] > sah12["build_ms"],
              f"frame {sah12['frame_ms']:.1f} → {sah32['frame_ms']:.1f} ms, build {sah12['build_ms']:.1f} → "
              f"{sah32['build_ms']:.1f} ms")
    if uniform_rows:
        times = [r["frame_ms"] for r in uniform_rows]
        spread = max(times) / min(times) - 1
        claim("on uniformly random spheres the methods are within ~15% of each other", spread <= 0.15,
              "frame times " + ", ".join(f"{r['method']} {r['frame_ms']:.1f}" for r in uniform_rows) +
              f" ms (spread {spread:.0%})")
    return out
