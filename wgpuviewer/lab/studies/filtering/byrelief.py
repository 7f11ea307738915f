"""The filtering paper's question answered per relief, not as one average: per relief and albedo class, the
visibility filters against plain EWA on the same footprint and tracer, case by case (wins and losses beyond both
rows' reference error), with a bootstrap interval of the mean difference; and the paper's cheap row-ends method
against its full method (time, depth fetches, PSNR) case by case. Shared by report.md and docs/filtering.md's
block, over one run or several (``merged``: each case tagged with its run, so runs never mix a case)."""

from __future__ import annotations

import math
from collections import defaultdict

import numpy as np

from .aggregate import FOLLOWS, _fmt, beyond_uncertainty, label, ranked

#: The visibility configurations the verdict is given for (label parts: filter, source, params, tracer).
VERDICT_CONFIGS = (("ewa_vis", "analytic", "", "maxmip"), ("ewa_vis", "displaced", "", "maxmip"),
                   ("ewa_vis", "displaced", "inherit=1", "pom32"))
#: The row-ends method against the full method: (rows label, full label) on the exact tracer.
ROW_ENDS = tuple((label("ewa_vis_rows", s, p), label("ewa_vis", s, p))
                 for s, p in (("displaced", ""), ("analytic", ""), ("displaced", "inherit=1")))
BOOTSTRAP = 4000  # resamples of the per-case differences
CONFIDENCE = 0.95
SEED = 0  # the interval is reproducible from results.csv alone


def merged(runs: dict[str, list[dict]]) -> list[dict]:
    """The rows of several runs (name -> rows), each case renamed ``run/case``."""
    return [{**row, "case": f"{name}/{row['case']}"} for name, rows in runs.items() for row in rows]


def bootstrap_mean(values: list[float], resamples: int = BOOTSTRAP, seed: int = SEED) -> tuple[float, float]:
    """The percentile bootstrap interval (CONFIDENCE) of the mean of ``values``; (nan, nan) without values."""
    data = np.asarray([v for v in values if math.isfinite(v)], np.float64)
    if data.size == 0:
        return math.nan, math.nan
    rng = np.random.default_rng(seed)
    means = data[rng.integers(0, data.size, (resamples, data.size))].mean(axis=1)
    tail = (1.0 - CONFIDENCE) / 2.0 * 100.0
    return float(np.percentile(means, tail)), float(np.percentile(means, 100.0 - tail))


def verdict(better: int, worse: int, low: float, high: float) -> str:
    """In words: holds (the interval above 0 and more wins than losses), fails (below 0, more losses), mixed."""
    if low > 0.0 and better > worse:
        return "holds"
    if high < 0.0 and worse > better:
        return "fails"
    if better == 0 and worse == 0:
        return "no difference"
    return "mixed"


def relief_classes(rows: list[dict]) -> dict[tuple[str, str], list[dict]]:
    """(relief, albedo class) -> its ranked rows, reliefs in the order they first appear."""
    groups = defaultdict(list)
    for row in ranked(rows):
        kind = "follows" if row["albedo"] in FOLLOWS else "independent"
        groups[(row["relief"], kind)].append(row)
    return dict(groups)


def verdict_rows(rows: list[dict]) -> list[dict]:
    """Per relief, albedo class and VERDICT_CONFIGS entry measured there: cases, wins and losses beyond the
    reference's error, the mean PSNR difference against plain EWA (same source and tracer), its bootstrap interval,
    the per-case range, the verdict."""
    out = []
    for (relief, kind), group in relief_classes(rows).items():
        for filter_name, source, params, tracer in VERDICT_CONFIGS:
            name, plain = label(filter_name, source, params, tracer), label("ewa", source, tracer=tracer)
            mine = [r for r in group if r["label"] == name]
            base = {r["case"]: r["psnr"] for r in group if r["label"] == plain}
            d = [r["psnr"] - base[r["case"]] for r in mine if r["case"] in base
                 and math.isfinite(r["psnr"] - base[r["case"]])]
            if not d:
                continue
            better, worse = beyond_uncertainty(mine, group, plain)
            low, high = bootstrap_mean(d)
            out.append({"relief": relief, "albedos": kind, "config": name, "cases": len(d), "better": better,
                        "worse": worse, "mean": float(np.mean(d)), "low": low, "high": high, "min": min(d),
                        "max": max(d), "verdict": verdict(better, worse, low, high)})
    return out


def verdict_table(rows: list[dict]) -> list[str]:
    lines = ["| relief | albedo | filter (source) [tracer] | cases | better / worse beyond the reference's error | "
             f"vs ewa, same source, dB: mean [{CONFIDENCE:.0%} bootstrap] | per-case min, max | the paper's claim |",
             "|---|---|---|---|---|---|---|---|"]
    for v in verdict_rows(rows):
        lines.append(f"| {v['relief']} | {v['albedos']} | `{v['config']}` | {v['cases']} | {v['better']} / "
                     f"{v['worse']} | {_fmt(v['mean'])} [{_fmt(v['low'])}, {_fmt(v['high'])}] | {_fmt(v['min'])}, "
                     f"{_fmt(v['max'])} | {v['verdict']} |")
    return lines


def row_ends(rows: list[dict]) -> list[dict]:
    """Per ROW_ENDS pair: cases, how many the row-ends method is slower in, the per-case time change and depth-fetch
    saving (ranges and medians, fractions of the full method's) and the PSNR difference's range."""
    valid = ranked(rows)
    out = []
    for rows_label, full_label in ROW_ENDS:
        full = {r["case"]: r for r in valid if r["label"] == full_label}
        pairs = [(r, full[r["case"]]) for r in valid if r["label"] == rows_label and r["case"] in full]
        pairs = [(a, b) for a, b in pairs if b["time_ratio"] > 0 and b["depth_fetches_per_pixel"] > 0]
        if not pairs:
            continue
        time = [a["time_ratio"] / b["time_ratio"] - 1.0 for a, b in pairs]
        fetches = [1.0 - a["depth_fetches_per_pixel"] / b["depth_fetches_per_pixel"] for a, b in pairs]
        psnr = [a["psnr"] - b["psnr"] for a, b in pairs]
        out.append({"rows": rows_label, "full": full_label, "cases": len(pairs), "slower": sum(t > 0 for t in time),
                    "time": (min(time), float(np.median(time)), max(time)),
                    "fetches": (min(fetches), float(np.median(fetches)), max(fetches)), "psnr": (min(psnr), max(psnr))})
    return out


def row_ends_lines(rows: list[dict]) -> list[str]:
    found = row_ends(rows)
    if not found:
        return ["- The row-ends method was not measured in this run."]
    return [f"- `{e['rows']}` against `{e['full']}`: slower in {e['slower']} of {e['cases']} cases, time "
            f"{e['time'][0]:+.0%} to {e['time'][2]:+.0%} (median {e['time'][1]:+.0%}); depth fetches saved "
            f"{e['fetches'][0]:.1%} to {e['fetches'][2]:.1%} (median {e['fetches'][1]:.1%}); PSNR "
            f"{_fmt(e['psnr'][0])} to {_fmt(e['psnr'][1])} dB." for e in found]


def section(rows: list[dict]) -> list[str]:
    """The per-relief verdict and the row-ends comparison, as report.md and the docs block give them."""
    return ["Visibility against plain EWA on the same footprint and tracer, per relief and albedo class (the albedo "
            "follows the relief: own, masked; independent of it: checker, stripes, photo). A case counts as better "
            "or worse only beyond both rows' reference error; the interval resamples the cases. \"holds\": the "
            "interval lies above 0 and the wins outnumber the losses; \"fails\": the reverse; \"mixed\": neither.",
            "", *verdict_table(rows), "", "The paper's cheap row-ends method against its full method, case by case "
            "(exact tracer; time and depth fetches as fractions of the full method's):", "", *row_ends_lines(rows)]
