"""The filtering study's outputs: ``results.csv`` (one row per case x configuration, ``suites.TABLE``), ``run.json``
(the header and the suite's settings), ``report.md`` (the recommendation, the answer to the filtering paper's
question, per-case numbers), ``pareto.png`` (error against GPU time, labels placed apart), ``distributions.png``
(per-case PSNR differences against trilinear and against bilinear) and side-by-side crops (``crops_CASE.png``:
reference and filters, with their difference images). ``rereport`` makes report.md and the plots again from a
results.csv (``wgpuviewer filtering --from-csv``), so a change of the report needs no new measurement.

Every number of the report is an aggregate of results.csv's valid rows (``void`` empty) of the ranked cases
(``role`` rank); the tuning cases appear only in their own section.
"""

from __future__ import annotations

import json
import math
from collections import defaultdict
from pathlib import Path

from wgpuviewer.core.errors import UserError
from wgpuviewer.core.io import write_bytes
from wgpuviewer.lab.harness.header import Header
from wgpuviewer.relief.filters import get_filter

from .aggregate import FOLLOWS, _fmt, _geomean, _mean, against, beyond_uncertainty, by_config, differences, label, ranked
from .pictures import write_crops, write_distributions, write_pareto
from .suites import BASELINE, BILINEAR, EXACT, RUN_FILE, TABLE, Suite
from .views import ALBEDOS, HEIGHT_SCALE, RELIEFS, TECHNIQUE, Case

__all__ = ["TABLE", "TITLE", "rereport", "write", "wanted_for_pictures", "recommendation"]

#: Albedo classes of the recommendation: does the albedo follow the relief's height?
NEAR_BEST_DB = 0.5  # "cheapest within this of the best"
TRACER_NAMES = {"maxmip": "exact (maxmip)", "pom32": "POM, 32 layers"}

TITLE = "Texture filtering on relief surfaces (Romanyuk & Dudnyk 2017)"


def wanted_for_pictures(case: Case, suite: Suite) -> bool:
    """Crops for the occluding cases with the albedos that follow the relief and the checker, at the suite's
    steepest angle up to 80 degrees, and the relief's smallest minification there."""
    angles = [c.angle for c in suite.cases if c.angle <= 80.0] or [c.angle for c in suite.cases]
    footprints = [c.footprint for c in suite.cases if c.relief == case.relief and c.angle == case.angle]
    return (case.occluding and case.albedo in ("own", "masked", "checker") and case.angle == max(angles)
            and case.footprint == min(footprints))


def write(out: Path, rows: list[dict], kept: list, record: dict) -> None:
    """The crops of the kept cases, then the plots and report.md (results.csv and run.json are written first)."""
    void = {r["label"] for r in rows if r["void"]}
    for result in kept:
        write_crops(out, result, void)
    write_report(out, rows, record)


def write_report(out: Path, rows: list[dict], record: dict) -> None:
    pictures = sorted(p.name for p in Path(out).glob("crops_*.png"))
    pareto = write_pareto(out / "pareto.png", rows)
    distributions = write_distributions(out / "distributions.png", rows)
    write_bytes(out / "report.md", markdown(rows, record, pictures, pareto, distributions).encode())


def rereport(csv: Path, out: Path) -> None:
    """report.md and the plots again from ``csv`` (and the run.json beside it) into ``out``; the crops are those
    already in ``out``."""
    rows = TABLE.read(csv)
    if not rows:
        raise UserError(f"--from-csv {csv}: no rows; give the results.csv of a filtering run")
    meta = Path(csv).parent / RUN_FILE
    if meta.is_file():
        record = json.loads(meta.read_text())
    else:
        record = {"title": TITLE, "command": f"(unknown: {csv} has no {RUN_FILE} beside it)",
                  "adapter": rows[0]["adapter"], "suite": "?", "started": None, "seconds": None, "void_notes": []}
    record["sources"] = [str(csv)]
    write_report(Path(out), rows, record)


# --- the recommendation ----------------------------------------------------------------------------------------


def groups_of(rows: list[dict]) -> dict[str, list[dict]]:
    """The recommendation's groups: occluding relief with an albedo that follows it, with one independent of it, and
    flat relief."""
    return {"relief, albedo follows it (own, masked)": [r for r in rows if r["occluding"] and r["albedo"] in FOLLOWS],
            "relief, albedo independent (checker, stripes, photo)":
                [r for r in rows if r["occluding"] and r["albedo"] not in FOLLOWS],
            "flat relief": [r for r in rows if not r["occluding"]]}


def recommendation(rows: list[dict]) -> list[str]:
    """Per group and tracer: the most accurate configuration, what it gains over trilinear and bilinear (mean and
    the per-case range), its cost, its flicker, and the cheapest configuration within NEAR_BEST_DB of it."""
    valid = ranked(rows)
    lines = ["| cases | tracer | most accurate: PSNR box / Gaussian ref | vs trilinear, dB: mean [per-case min, max] "
             "| vs bilinear, dB: mean [min, max] | time x trilinear | flicker dB | cheapest within "
             f"{NEAR_BEST_DB} dB: PSNR, time x trilinear, flicker dB | trilinear's flicker dB | cases |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for title, subset in groups_of(valid).items():
        for tracer in TRACER_NAMES:
            mine = [r for r in subset if r["tracer"] == tracer]
            if not mine:
                continue
            groups = by_config(mine)
            stats = {name: (_mean([r["psnr"] for r in g]), _geomean([r["time_ratio"] for r in g]),
                            _mean([r["flicker_psnr"] for r in g])) for name, g in groups.items()}
            best = max(stats, key=lambda k: stats[k][0] if math.isfinite(stats[k][0]) else -1e9)
            near = [k for k, (p, t, _) in stats.items() if p >= stats[best][0] - NEAR_BEST_DB and math.isfinite(t)]
            cheap = min(near, key=lambda k: stats[k][1]) if near else best
            tri, bil = BASELINE.on(tracer).label, BILINEAR.on(tracer).label
            cells = []
            for base in (tri, bil):
                d = differences(mine, best, base)
                cells.append(f"{_fmt(_mean(d))} [{_fmt(min(d) if d else math.nan)}, {_fmt(max(d) if d else math.nan)}]")
            lines.append(
                f"| {title} | {TRACER_NAMES[tracer]} | `{best}` {_fmt(stats[best][0], '.2f')} / "
                f"{_fmt(_mean([r['psnr_gauss'] for r in groups[best]]), '.2f')} | {cells[0]} | {cells[1]} | "
                f"{_fmt(stats[best][1], '.2f')} | {_fmt(stats[best][2], '.1f')} | `{cheap}` "
                f"{_fmt(stats[cheap][0], '.2f')}, {_fmt(stats[cheap][1], '.2f')}, {_fmt(stats[cheap][2], '.1f')} | "
                f"{_fmt(stats.get(tri, (0, 0, math.nan))[2], '.1f')} | {len({r['case'] for r in mine})} |")
    return lines


def derivative_sources(rows: list[dict]) -> list[str]:
    """Plain EWA per derivative source and group (exact tracer): mean PSNR and the gain over trilinear."""
    valid = [r for r in ranked(rows) if r["tracer"] == EXACT]
    lines = ["| cases | " + " | ".join(f"ewa ({s}): PSNR, vs trilinear, time x trilinear"
                                      for s in ("uv", "displaced", "analytic")) + " |", "|---|---|---|---|"]
    for title, subset in groups_of(valid).items():
        if not subset:
            continue
        cells = []
        for source in ("uv", "displaced", "analytic"):
            name = label("ewa", source)
            mine = [r for r in subset if r["label"] == name]
            cells.append(f"{_fmt(_mean([r['psnr'] for r in mine]), '.2f')}, "
                         f"{_fmt(_mean(differences(subset, name, BASELINE.label)))}, "
                         f"{_fmt(_geomean([r['time_ratio'] for r in mine]), '.2f')}")
        lines.append(f"| {title} | {' | '.join(cells)} |")
    return lines


def measures(rows: list[dict], start_rays: int) -> list[str]:
    """The reference's own error per albedo and how often it was raised from ``start_rays``; the traced derivative
    sources' raw length ratios and how often they were bounded (exact tracer, ranked cases)."""
    rank = [r for r in rows if r["role"] == "rank" and r["tracer"] == EXACT]
    one = [r for r in rank if r["label"] == BASELINE.label]  # one row per case
    if not one:
        return []
    ranges = "; ".join(f"{a} {min(v):.1f}–{max(v):.1f}" for a in ALBEDOS
                       if (v := [r["reference_psnr_half"] for r in one if r["albedo"] == a]))
    raised = sum(r["reference_rays"] > start_rays for r in one)
    lines = [f"- Reference, half against full rays (PSNR dB, per albedo): {ranges}; raised from {start_rays} to "
             f"{max(r['reference_rays'] for r in one)} rays per side in {raised} of {len(one)} cases; every compared "
             f"difference resolved in {sum(bool(r['reference_resolved']) for r in one)}."]
    for source in ("displaced", "analytic"):
        g = [r for r in rank if r["label"] == label("ewa", source) and r["occluding"]]
        if g:
            top = max(r["ratio_max"] for r in g)
            p99 = max(r["ratio_p99"] for r in g)
            lines.append(f"- `{source}` derivatives on occluding relief: raw length up to {top:.0f}x the unperturbed "
                         f"one (a case's 99th percentile up to {p99:.1f}x); "
                         f"bounded in {_mean([r['bounded_share'] for r in g]):.1%} of the pixels on average, at most "
                         f"{max(r['bounded_share'] for r in g):.1%}.")
    return lines


# --- the paper's question -------------------------------------------------------------------------------------


def visibility(rows: list[dict]) -> list[str]:
    """Visibility's effect per group, tracer and source: against plain EWA on the same footprint (box / Gaussian
    reference / occluded pixels), the cases where it wins or loses by more than both rows' reference uncertainty,
    against trilinear and bilinear, cost."""
    valid = [r for r in ranked(rows) if r["occluding"]]
    lines = ["| cases | filter | vs ewa, same source: box / Gaussian / occluded px | cases better / worse beyond "
             "the reference's error | vs trilinear | vs bilinear | time x trilinear | time x ewa | cases |",
             "|---|---|---|---|---|---|---|---|---|"]
    for title, subset in list(groups_of(valid).items())[:2] + [("all occluding cases", valid)]:
        for name, group in by_config(subset).items():
            row0 = group[0]
            if not row0["filter"].startswith("ewa_vis"):
                continue
            plain = label("ewa", row0["derivatives"], tracer=row0["tracer"])
            box, gauss, occl = (_mean(differences(subset, name, plain, k))
                                for k in ("psnr", "psnr_gauss", "psnr_occluded"))
            better, worse = beyond_uncertainty(group, subset, plain)
            t = _geomean([r["time_ratio"] for r in group])
            te = t / _geomean([r["time_ratio"] for r in subset if r["label"] == plain])
            lines.append(f"| {title} | `{name}` | {_fmt(box)} / {_fmt(gauss)} / {_fmt(occl)} | {better} / {worse} | "
                         f"{_fmt(_mean(differences(subset, name, BASELINE.on(row0['tracer']).label)))} | "
                         f"{_fmt(_mean(differences(subset, name, BILINEAR.on(row0['tracer']).label)))} | "
                         f"{_fmt(t, '.1f')} | {_fmt(te, '.1f')} | {len(group)} |")
    return lines


def weighting(rows: list[dict]) -> list[str]:
    """Inherit against drop, per group and configuration."""
    valid = [r for r in ranked(rows) if r["occluding"]]
    lines = []
    for title, subset in list(groups_of(valid).items())[:2]:
        for name in by_config(subset):
            if "inherit=1" not in name:
                continue
            drop = name.replace(" inherit=1", "")
            d = differences(subset, name, drop)
            if d:
                lines.append(f"- {title}, `{name}` against `{drop}`: {_fmt(_mean(d))} dB on average "
                             f"[{_fmt(min(d))}, {_fmt(max(d))}] over {len(d)} cases.")
    return lines or ["- The visibility filters' `inherit` weighting was not measured in this run."]


def tuning(rows: list[dict]) -> list[str]:
    tune = [r for r in rows if r["role"] == "tune" and not r["void"]]
    if not tune:
        return ["No tuning cases in this run."]
    lines = ["| configuration | PSNR box ref | PSNR Gaussian ref | cases |", "|---|---|---|---|"]
    stats = []
    for name, group in by_config(tune).items():
        stats.append((name, _mean([r["psnr"] for r in group]), _mean([r["psnr_gauss"] for r in group]), len(group)))
    for name, box, gauss, n in sorted(stats, key=lambda s: -s[1]):
        lines.append(f"| `{name}` | {_fmt(box, '.2f')} | {_fmt(gauss, '.2f')} | {n} |")
    ewa = [s for s in stats if s[0].startswith("ewa alpha=")]
    if ewa:
        box_best = max(ewa, key=lambda s: s[1])[0]
        gauss_best = max(ewa, key=lambda s: s[2])[0]
        default = get_filter("ewa").defaults()["alpha"]
        follows = (f"the default alpha ({default:g}) is this best" if box_best == f"ewa alpha={default:g} (analytic)"
                   else f"the default alpha ({default:g}) is not this best: set it from these cases and rank again")
        lines += ["", f"Best on the tuning cases ({', '.join(sorted({r['case'] for r in tune}))}): `{box_best}` "
                      f"against the box reference, `{gauss_best}` against the Gaussian one. The ranked cases use "
                      f"the default alpha and Heckbert's 2; {follows}."]
    return lines


def flicker(rows: list[dict]) -> list[str]:
    measured = [r for r in ranked(rows) if math.isfinite(r["flicker_psnr"])]
    if not measured:
        return ["No flicker sweep in this run."]
    own = _mean([r["flicker_reference_psnr"] for r in measured])
    lines = [f"Frame-to-frame change against the reference's over {len({r['case'] for r in measured})} cases "
             f"(the reference at half the rays scores {own:.1f} dB on the same measure):", "",
             "| configuration | flicker PSNR dB | change / the reference's change | PSNR dB (same cases) |",
             "|---|---|---|---|"]
    stats = [(name, _mean([r["flicker_psnr"] for r in g]), _mean([r["flicker_ratio"] for r in g]),
              _mean([r["psnr"] for r in g])) for name, g in by_config(measured).items()]
    for name, fp, ratio, p in sorted(stats, key=lambda s: -s[1]):
        lines.append(f"| `{name}` | {fp:.2f} | {ratio:.2f} | {p:.2f} |")
    return lines


# --- report.md -------------------------------------------------------------------------------------------------


def _table(rows: list[dict]) -> list[str]:
    lines = ["| filter (derivatives) [tracer] | PSNR dB box ref | PSNR dB Gaussian ref | ± reference | SSIM | "
             "PSNR occluded px | vs trilinear | vs bilinear | time x trilinear | texels/px | depth fetches/px | "
             "hidden texels/px | capped |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    tri, bil = against(rows, BASELINE), against(rows, BILINEAR)
    for name, group in sorted(by_config(rows).items(), key=lambda kv: -_mean([r["psnr"] for r in kv[1]])):
        lines.append(
            f"| {name} | {_mean([r['psnr'] for r in group]):.2f} | {_mean([r['psnr_gauss'] for r in group]):.2f} | "
            f"{_mean([r['psnr_uncertainty'] for r in group]):.2f} | {_mean([r['ssim'] for r in group]):.3f} | "
            f"{_fmt(_mean([r['psnr_occluded'] for r in group]), '.2f')} | {_fmt(_mean(tri.get(name, [])))} | "
            f"{_fmt(_mean(bil.get(name, [])))} | {_geomean([r['time_ratio'] for r in group]):.2f} | "
            f"{_mean([r['texels_per_pixel'] for r in group]):.1f} | "
            f"{_mean([r['depth_fetches_per_pixel'] for r in group]):.0f} | "
            f"{_mean([r['hidden_per_pixel'] for r in group]):.2f} | {_mean([r['capped_share'] for r in group]):.1%} |")
    return lines


def _header(record: dict) -> Header:
    import datetime

    started = datetime.datetime.fromisoformat(record["started"]) if record.get("started") else None
    return Header(record.get("title", TITLE), record["command"], record["adapter"], record["suite"], started,
                  record.get("seconds"), tuple(record.get("sources", ())))


def markdown(rows: list[dict], record: dict, pictures: list[str], pareto: str | None,
             distributions: str | None) -> str:
    header = _header(record)
    timer = rows[0]["timer"] if rows else "?"
    software = any(word in header.adapter.lower() for word in ("llvmpipe", "lavapipe", "swiftshader", "warp"))
    rank = [r for r in rows if r["role"] == "rank"]
    cases = sorted({r["case"] for r in rank})
    sweep = record.get("flicker") or {}
    void_labels = sorted({r["label"] for r in rows if r["void"]})
    lines = [
        *header.lines(),
        f"- timer: {timer}" + (" — **a CPU-emulated adapter**: GPU times are ratios measured side by side in one "
                               "run, not a GPU's" if software else ""),
        f"- {len(cases)} ranked cases x {len({r['label'] for r in rank})} configurations, "
        f"{len({r['case'] for r in rows if r['role'] == 'tune'})} tuning cases; frames "
        f"{'x'.join(str(v) for v in record.get('size', ['?']))}; reference "
        f"{record.get('reference', '?')}x{record.get('reference', '?')} rays per pixel, raised up to "
        f"{record.get('max_reference', '?')}x{record.get('max_reference', '?')} where its own error hides a compared "
        "difference; " + (f"flicker: {sweep['frames']} frames of {sweep['size'][0]}x{sweep['size'][1]}, "
                          f"{sweep['step']} texel per frame, reference {sweep['rays']}x{sweep['rays']}, at "
                          f"{', '.join(f'{a:g}°' for a in sweep['angles'])} and "
                          f"{', '.join(f'x{f:g}' for f in sweep['footprints'])}" if sweep else "no flicker sweep"),
        *([f"- **{record['stopped']}**: this report covers only those"] if record.get("stopped") else []),
        "",
        f"Technique `{TECHNIQUE}` (exact hits) for the reference and the rows without a tracer tag; `[pom32]`: the "
        f"same after POM with 32 layers. Relief depth {HEIGHT_SCALE} UV units per tile; errors of the unlit, filtered "
        "albedo against the supersampled reference (method: docs/filtering.md). Aggregates use only the valid rows "
        "of the ranked cases.", "",
    ]
    if void_labels:
        lines += ["**Void rows** (kept in results.csv with the reason in `void`, left out of every aggregate and "
                  f"plot): {', '.join(f'`{v}`' for v in void_labels)}. "
                  + " ".join(record.get("void_notes", [])), ""]
    lines += ["## Recommendation", "", *recommendation(rows), "", "Plain EWA by derivative source (exact tracer):",
              "", *derivative_sources(rows), "", "## Visibility (the paper's question)", "", *visibility(rows), "",
              "The substitute inheriting the hidden texel's weight, against dropping it:", "", *weighting(rows), "",
              "## Visibility by relief, case by case", "", *by_relief(rows), ""]
    if pareto:
        lines += [f"![error against time]({pareto})", ""]
    if distributions:
        lines += [f"![per-case differences]({distributions})", ""]
    for picture in pictures:
        lines += [f"![crops]({picture})", ""]
    lines += ["## Flicker (camera sweep)", "", *flicker(rows), "",
              "## Tuning (EWA's alpha, on cases never ranked)", "", *tuning(rows), ""]
    for title, subset in (("Relief with occlusion", [r for r in ranked(rows) if r["occluding"]]),
                          ("Flat relief", [r for r in ranked(rows) if not r["occluding"]])):
        if subset:
            lines += [f"## {title} ({len({r['case'] for r in subset})} cases)", "", *_table(subset), ""]
    lines += per_case(rows, record)
    lines += ["", "Reliefs: " + "; ".join(f"`{k}` {v}" for k, v in RELIEFS.items()) + ".",
              "Albedos: " + "; ".join(f"`{k}` {v}" for k, v in ALBEDOS.items()) + ".", ""]
    return "\n".join(lines)


def by_relief(rows: list[dict]) -> list[str]:
    from .byrelief import section  # it builds on this module's groups and counts

    return section(rows)


def per_case(rows: list[dict], record: dict) -> list[str]:
    """The report's per-case table (exact tracer): the reference's own error, the best valid configuration, the
    baselines, visibility's and the weighting's differences, EWA's capped share, the displaced ratio."""
    lines = ["## Per case", "",
             "The reference's own error: its half-ray version's PSNR against it; rays: where that error hid a "
             "compared difference (visibility against EWA, inherit against drop, EWA against the baselines) the "
             "rays were doubled up to the suite's most; resolved: every such difference of at least "
             f"{0.1} dB exceeds both rows' reference uncertainty.", "",
             "| case | occluded px | reference rays | half vs full, PSNR dB | resolved | best valid | its PSNR | "
             "trilinear | bilinear | ewa_vis - ewa (displaced / analytic) | inherit - drop (displaced) | "
             "ewa capped | displaced ratio p99 / max |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    intro = measures(rows, record.get("reference", 16))
    if intro:
        lines[-3:-3] = [*intro, ""]
    per_case = defaultdict(list)
    for r in ranked(rows):
        if r["tracer"] == EXACT:
            per_case[r["case"]].append(r)
    for name, group in per_case.items():
        psnrs = {r["label"]: r["psnr"] for r in group}
        best = max(group, key=lambda r: r["psnr"] if math.isfinite(r["psnr"]) else -1e9)
        base = group[0]
        disp = next((r for r in group if r["label"] == label("ewa", "displaced")), base)
        ewa = next((r for r in group if r["label"] == label("ewa", "analytic")), base)

        def delta(a, b, psnrs=psnrs):
            return _fmt(psnrs[a] - psnrs[b]) if a in psnrs and b in psnrs else "–"

        vis = " / ".join(delta(label("ewa_vis", s), label("ewa", s)) for s in ("displaced", "analytic"))
        lines.append(
            f"| {name} | {base['occluded_share']:.1%} | {base['reference_rays']} | {base['reference_psnr_half']:.1f} | "
            f"{'yes' if base['reference_resolved'] else 'no'} | {best['label']} | {best['psnr']:.2f} | "
            f"{_fmt(psnrs.get(BASELINE.label, math.nan), '.2f')} | {_fmt(psnrs.get(BILINEAR.label, math.nan), '.2f')} "
            f"| {vis} | {delta(label('ewa_vis', 'displaced', 'inherit=1'), label('ewa_vis', 'displaced'))} | "
            f"{ewa['capped_share']:.1%} | {disp['ratio_p99']:.1f} / {disp['ratio_max']:.3g} |")
    return lines
