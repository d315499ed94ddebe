"""The report's claims (§4.2, §5.2), tested on our numbers with the protocol's verdicts: "holds" or
"does NOT hold" only when the paired ratio's whole interval lies on one side of the claim's
threshold, else "inconclusive". The data are never bent to fit."""

from __future__ import annotations

from .protocol import FAILS, HOLDS, Interval, all_of, at_least, at_most, paired, paired_ratio, within
from .report import MEAN_READINGS, REPORT_TABLE1, median_ms, report_row, samples


def _row(rows, method):
    return next((r for r in rows if r["method"] == method), None)


def _sah_rows(rows):
    return [r for r in rows if r["method"].startswith("sah") or r["method"] == "sweep_sah"]


def _ratio(a: dict, b: dict, name: str = "frame") -> Interval:
    return paired_ratio(samples(a, name), samples(b, name))


def _report_ratio(a: str, b: str, column: int = 0) -> str:
    """The report's own ratio of the same two methods (column 0 frame, 1 build), as text."""
    ra, rb = REPORT_TABLE1.get(report_row(a)), REPORT_TABLE1.get(report_row(b))
    return f" (report: {ra[column] / rb[column]:.2f})" if ra and rb else ""


def _claim(out, section, text, verdict, detail):
    out.append(
        {
            "claim": text,
            "section": section,
            "verdict": verdict,
            "holds": True if verdict == HOLDS else False if verdict == FAILS else None,
            "detail": detail,
        }
    )


def report_checks(rows: list[dict], uniform_rows: list[dict] | None = None) -> list[dict]:
    """One record per claim: claim, section, verdict, holds (True, False, None = inconclusive), detail."""
    out: list[dict] = []
    _check_sah_fastest(out, rows)
    median, sah_rows = _row(rows, "median"), _sah_rows(rows)
    best_sah = min(sah_rows, key=lambda r: median_ms(r, "frame")) if sah_rows else None
    for reading in MEAN_READINGS:
        mean = _row(rows, reading)
        if mean and median:
            r = _ratio(mean, median)
            _claim(
                out,
                "§5.2",
                f"{reading} is clearly faster than median (at least 10% less frame time)",
                at_most(r, 0.9),
                f"{reading}/median frame time {r.text(2)}{_report_ratio(reading, 'median')}",
            )
        if mean and median and best_sah:
            _check_close_to_sah(out, reading, mean, median, best_sah)
    _check_heights(out, rows)
    _check_bins(out, rows)
    _check_sah_build(out, rows)
    if uniform_rows and len(uniform_rows) > 1:
        fastest = min(uniform_rows, key=lambda r: median_ms(r, "frame"))
        slowest = max(uniform_rows, key=lambda r: median_ms(r, "frame"))
        r = _ratio(slowest, fastest)
        _claim(
            out,
            "§4.2",
            "on uniformly random spheres the methods are within 15% of each other",
            at_most(r, 1.15),
            f"slowest/fastest frame time ({slowest['method']}/{fastest['method']}) {r.text(2)}; medians "
            + ", ".join(f"{u['method']} {median_ms(u, 'frame'):.1f}" for u in uniform_rows)
            + " ms",
        )
        _check_uniform_heights(out, rows, uniform_rows)
    return out


def _height_spread(rows) -> float:
    heights = [r["height"] for r in rows]
    return max(heights) / max(min(heights), 1)


def _check_uniform_heights(out, rows, uniform_rows):
    """§4.2: on random spheres the methods give "similar frame time and tree height compared to
    the results in Table 1": the tallest tree over the lowest, there against here (the frame
    times alone were checked)."""
    if len(rows) < 2:
        return
    there, here = _height_spread(uniform_rows), _height_spread(rows)
    _claim(
        out,
        "§4.2",
        "on uniformly random spheres the tree heights are more alike than on this scene",
        HOLDS if there < here else FAILS,
        f"tallest/lowest height {there:.2f} ("
        + ", ".join(f"{u['method']} {u['height']}" for u in uniform_rows)
        + f") against {here:.2f} here",
    )


def _to_midway(mean, median, sah):
    """mean's frame time over the point midway between SAH's and median's: below 1, mean is nearer SAH."""
    return 2 * mean / (median + sah)


def _check_close_to_sah(out, reading, mean, median, sah):
    """§5.2 "came respectably close to the performance of SAH": nearer to SAH's frame time than to
    median's (a ratio to the midway point, which one stalled sample cannot blow up as it could a
    ratio of differences)."""
    share = paired(_to_midway, samples(mean, "frame"), samples(median, "frame"), samples(sah, "frame"))
    rep = [REPORT_TABLE1.get(report_row(m)) for m in (reading, "median", sah["method"])]
    said = f" (report: {_to_midway(*(r[0] for r in rep if r is not None)):.2f})" if all(rep) else ""
    _claim(
        out,
        "§5.2",
        f"{reading} comes close to SAH (its frame time nearer SAH's than median's)",
        at_most(share, 1.0),
        f"{reading} / midway(median, {sah['method']}) frame time {share.text(2)}{said}",
    )


def _check_sah_fastest(out, rows):
    """§4.2 "SAH outperformed the others": every SAH row faster than every other row (the best
    SAH row alone was tested: one SAH row slower than a simple split would have passed)."""
    sah_rows = _sah_rows(rows)
    others = [r for r in rows if r not in sah_rows]
    if not sah_rows or not others:
        return
    ratios = {(s["method"], o["method"]): _ratio(s, o) for s in sah_rows for o in others}
    _claim(
        out,
        "§4.2",
        "SAH has the lowest frame time",
        all_of([at_most(r, 1.0) for r in ratios.values()]),
        "; ".join(
            f"{s['method']}/other frame time: "
            + ", ".join(f"{o} {r.text(2)}" for (m, o), r in ratios.items() if m == s["method"])
            for s in sah_rows
        ),
    )


def _check_heights(out, rows):
    heights = ", ".join(f"{r['method']} {r['height']}" for r in rows)
    median = _row(rows, "median")
    if median and len(rows) > 1:
        others = [r for r in rows if r is not median]
        tied = [r["method"] for r in others if r["height"] == median["height"]]
        # "a smaller height" (§4.2) than the others: a tie for the lowest does not hold
        _claim(
            out,
            "§4.2",
            "median gives the lowest tree",
            HOLDS if all(median["height"] < r["height"] for r in others) else FAILS,
            f"heights: {heights} (report: median 20, mean 34, SAH 30)"
            + (f"; as low as median: {', '.join(tied)}" if tied else ""),
        )
    for reading in MEAN_READINGS:
        mean = _row(rows, reading)
        rivals = [r for r in rows if r["method"] not in MEAN_READINGS]
        if mean and rivals:
            tallest = max(r["height"] for r in rivals)
            _claim(
                out,
                "§4.2",
                f"{reading} gives the tallest tree (the most unbalanced)",
                HOLDS if mean["height"] > tallest else FAILS,
                f"{reading} {mean['height']} against " + ", ".join(f"{r['method']} {r['height']}" for r in rivals),
            )


def _check_bins(out, rows):
    sah12, sah32 = _row(rows, "sah12"), _row(rows, "sah32")
    if not (sah12 and sah32):
        return
    frame, build = _ratio(sah32, sah12), _ratio(sah32, sah12, "build")
    _claim(
        out,
        "§4.2",
        "32 bins instead of 12 change the frame time little (within 10%)",
        within(frame, 0.10),
        f"sah32/sah12 frame time {frame.text(3)}{_report_ratio('sah32', 'sah12')}",
    )
    _claim(
        out,
        "§4.2",
        "32 bins instead of 12 increase the build time drastically (at least 1.5×)",
        at_least(build, 1.5),
        f"sah32/sah12 build time {build.text(2)}{_report_ratio('sah32', 'sah12', 1)}",
    )


def _check_sah_build(out, rows):
    sah12 = _row(rows, "sah12")
    simple = [r for r in rows if r["method"] in ("median", *MEAN_READINGS)]
    if not sah12 or not simple:
        return
    ratios = {r["method"]: _ratio(sah12, r, "build") for r in simple}
    _claim(
        out,
        "§4.2",
        "SAH (12 bins) takes longer to build than median and mean",
        all_of([at_least(r, 1.0) for r in ratios.values()]),
        "sah12/other build time: "
        + ", ".join(f"{m} {r.text(2)}{_report_ratio('sah12', m, 1)}" for m, r in ratios.items()),
    )
