"""``report.md`` of the perspective study, from its rows (``run.TABLE``); the plots are ``plots``. Every number in
the report is computed here from the measurements; nothing is typed in.

Errors are in screen pixels first (the texel error over the pixel's texel footprint: how far on screen the sample
is off), texels beside them where the texture's own scale matters (coordinate magnitude, the relief tie-back).
"""

from __future__ import annotations

import numpy as np

from wgpuviewer.lab.harness.plots import MISSING

from .methods import ADAPTIVE_FRACTIONS, METHODS, PARALLEL_THREADS
from .selection import (
    APPROXIMATIONS,
    BUDGET_PX,
    DRIFT_BUDGETS,
    MITIGATIONS,
    PAPER_F32,
    RECIPROCAL,
    _err,
    _f,
    _finite,
    _named,
    first_row,
    fitted_length,
    power_fit,
    select_rows,
    single_precision,
    speed_frames,
    speed_row,
)
from .tables import (
    adaptive_table,
    check_lines,
    compiled_table,
    gpu_table,
    operations_table,
    sweep_table,
    tieback_table,
    tile_table,
)
from .threads_report import section as threads_section


def every_row(_row) -> bool:
    return True


#: The regimes the recommendation covers: (label, sweep, the rows' condition).
REGIMES = (
    ("GPU and tile rasteriser spans (8–64 px of a row, each from an exact start)", "tile", every_row),
    ("frame rows (up to 4096 px)", "span_length", lambda r: r["span_length"] <= 4096),
    ("single long spans (over 4096 px)", "span_length", lambda r: r["span_length"] > 4096),
    ("moderate tilt (up to 80°)", "tilt", lambda r: r["tilt_deg"] <= 80),
    ("grazing (85° to 89.9°)", "tilt", lambda r: is_grazing(r)),
    ("large coordinates (offsets of 10^4 texels and more)", "magnitude", lambda r: r["offset_texels"] >= 1e4),
)


# --- the recommendation -----------------------------------------------------------------------------------------


def regime_worst(rows, sweep: str, condition, method: str) -> float:
    """The worst pixel's error (screen pixels) of ``method`` over the regime's configurations (NaN: not measured)."""
    errors = [r["max_err_px"] for r in select_rows(rows, sweep=sweep, method=method,
                                                   precision=single_precision(method))
              if condition(r) and _finite(r["max_err_px"])]
    return max(errors) if errors else float("nan")


def cost_row(rows, sweep: str, method: str):
    """Where a regime's cost is measured: the compiled timing on tiles for the tile regime, else on the first speed
    frame."""
    if sweep == "tile":
        return first_row(rows, sweep="speed_tile", method=method)
    return speed_row(rows, method)


def cheapest_within(rows, sweep: str, condition, key: str, budget: float = BUDGET_PX):
    """(method, its cost ratio ``key`` (``cost_row``), its worst error in the regime, the other methods within the
    budget whose ratio lies within the cheapest one's spread of it) of the cheapest method whose worst error stays
    within ``budget``; None when none does or nothing was measured."""
    found = []
    for name in METHODS:
        worst = regime_worst(rows, sweep, condition, name)
        timing = cost_row(rows, sweep, name)
        if _finite(worst) and worst <= budget and timing and _finite(timing[key]):
            found.append((timing[key], name, worst, timing[key.replace("ratio", "spread")]))
    if not found:
        return None
    ratio, name, worst, spread = min(found)
    tied = [n for r, n, _, _ in sorted(found) if n != name and r <= ratio * (1 + spread)]
    return name, ratio, worst, tied


def first_reaching(rows, sweep: str, key: str, method: str, budget: float):
    """The smallest sweep value (``key``) at which ``method``'s worst pixel reaches ``budget`` pixels, or None."""
    points = sorted((r[key], r["max_err_px"]) for r in select_rows(rows, sweep=sweep, method=method,
                                                                   precision=single_precision(method))
                    if _finite(r["max_err_px"]))
    return next((p for p, e in points if e >= budget), None)


def recommendation(rows) -> list[str]:
    frames = speed_frames(rows)
    if not frames:
        return ["Not measured: the run has no speed frame."]
    w, h = frames[0]
    tile = first_row(rows, sweep="speed_tile")
    lines = [
        f"Cost: compiled CPU time per texel on a {w} × {h} frame (tilt {_f(speed_row(rows, 'direct')['tilt_deg'])}°"
        + (f"; for the tile regime, the same frame in spans of {int(tile['span_length'])} pixels" if tile else "")
        + ") as a ratio to `direct`, for the scalar loop (the paper's platform: one pixel at a time) and the SIMD "
        f"build. Error: the worst pixel, in screen pixels, over every configuration of the regime. Budget: "
        f"{_f(BUDGET_PX)} pixel. Methods whose time lies within the cheapest one's spread over repeats (interquartile "
        f"range over median) are as cheap as this run can tell.",
        "",
        "| regime | cheapest within the budget, scalar loop | cheapest within the budget, SIMD build | "
        "`incremental` there | `direct` there |",
        "|---|---|---|---|---|",
    ]
    for label, sweep, condition in REGIMES:
        if not any(condition(r) for r in select_rows(rows, sweep=sweep)):
            continue
        cells = [label]
        for key in ("scalar_ratio", "simd_ratio"):
            best = cheapest_within(rows, sweep, condition, key)
            if best is None:
                cells.append(f"none within {_f(BUDGET_PX)} px")
                continue
            name, ratio, worst, tied = best
            cells.append(f"`{name}`: {_f(ratio)}× `direct`, ≤ {_f(worst)} px"
                         + (f" (as cheap within the spread: {', '.join(f'`{n}`' for n in tied)})" if tied else ""))
        for name in ("incremental", "direct"):
            cells.append(f"{_f(regime_worst(rows, sweep, condition, name))} px")
        lines.append("| " + " | ".join(cells) + " |")
    lines += ["", *(f"- {text}" for text in framing(rows))]
    return lines


def framing(rows) -> list[str]:
    """The practical reading of the table: where the drift matters at all, and what each remedy costs there."""
    out = []
    tiles = select_rows(rows, sweep="tile")
    if tiles:
        widths = sorted({r["span_length"] for r in tiles})
        tilts = sorted({r["tilt_deg"] for r in tiles})
        frame = int(select_rows(rows, sweep="tilt")[0]["span_length"]) if select_rows(rows, sweep="tilt") else 0
        worst = regime_worst(rows, "tile", every_row, "incremental")
        out.append(f"**Short spans.** GPU and tile rasterisers walk spans of "
                   f"{'–'.join(str(int(w)) for w in (widths[0], widths[-1]))} pixels, each from an exact start "
                   f"(the tile sweep: {frame}-pixel rows at {'/'.join(f'{t:g}' for t in tilts)}° cut into such "
                   f"spans): `incremental` errs by at most {_f(worst)} px there "
                   f"({_f(max(r['max_err'] for r in select_rows(tiles, method='incremental')))} texels), `direct` by "
                   f"{_f(regime_worst(rows, 'tile', every_row, 'direct'))} px; the drift is "
                   f"{_f(BUDGET_PX / worst, 2)}× below the budget there.")
    reach = first_reaching(rows, "span_length", "span_length", "incremental", BUDGET_PX)
    if reach is not None:
        longest = max(r["span_length"] for r in select_rows(rows, sweep="span_length"))
        remedies = []
        for name in ("reanchor_64", "reanchor_16", "direct", "span_rcp"):
            timing = speed_row(rows, name)
            if timing:
                remedies.append(f"`{name}` {_f(_err(rows, 'span_length', name, span_length=longest))} px at "
                                f"{_f(timing['scalar_ratio'])}× `direct`'s scalar time")
        out.append(f"**Long single spans.** `incremental`'s worst pixel first reaches {_f(BUDGET_PX)} px at "
                   f"L = {int(reach)} (tilt {rows_tilt(rows)}°; "
                   f"{_f(_err(rows, 'span_length', 'incremental', span_length=longest))} px at L = {int(longest)}); "
                   f"there " + ", ".join(remedies) + ".")
    offset = first_reaching(rows, "magnitude", "offset_texels", "incremental", BUDGET_PX)
    direct_offset = first_reaching(rows, "magnitude", "offset_texels", "direct", BUDGET_PX)
    if offset is not None:
        text = (f"**Large coordinates.** At L = {int(select_rows(rows, sweep='magnitude')[0]['span_length'])}, "
                f"`incremental` reaches {_f(BUDGET_PX)} px at an offset of {offset:g} texels")
        if direct_offset is not None:
            text += (f" and `direct` at {direct_offset:g} (float32's spacing there: "
                     f"{_f(float(np.spacing(np.float32(direct_offset))))} texels)")
        else:
            text += ", `direct` at no measured offset"
        out.append(text + ": what is lost is the coordinates' own float32 bits, which no evaluation order recovers; "
                          "texture coordinates wrapped per object (a whole number of tiles subtracted in float64, "
                          "before they become float32) stay small (the relief tie-back below measures the same for "
                          "the relief techniques).")
    grazing = [n for n in APPROXIMATIONS if _finite(regime_worst(rows, "tilt", is_grazing, n))]
    tilts = sorted(t for t in {r["tilt_deg"] for r in select_rows(rows, sweep="tilt")} if is_grazing({"tilt_deg": t}))
    if grazing:
        ends = dict.fromkeys((tilts[0], tilts[-1]))
        parts = ", ".join(f"`{n}` " + " and ".join(f"{_f(_err(rows, 'tilt', n, tilt_deg=t))} px at {t:g}°" for t in ends)
                          + f" ({_f(max_exact(rows, n))} exact evaluations per pixel at most)" for n in grazing)
        out.append(f"**Approximations at grazing angles**: {parts}. Fixed subdivisions spend the same anchors at "
                   f"every angle; the adaptive ones spend more where q changes fast and hold their bound.")
    return out


def is_grazing(row) -> bool:
    return 85 <= row["tilt_deg"] < 90


def max_exact(rows, name: str) -> float:
    """The most exact evaluations per pixel ``name`` made in a grazing configuration of the tilt sweep."""
    values = [r["exact_per_pixel"] for r in select_rows(rows, sweep="tilt", method=name) if is_grazing(r)]
    return max(values) if values else float("nan")


# --- the answers ------------------------------------------------------------------------------------------------


def gpu_label(software: bool) -> str:
    """What the GPU times are times of: a software adapter runs the kernels on the CPU."""
    return "software GPU adapter (its kernels run on the CPU)" if software else "GPU"


def answers(rows: list[dict], suite, software: bool) -> list[str]:
    out = []
    for w, h in speed_frames(rows):
        here = [r for r in select_rows(rows, sweep="speed", span_length=w, spans=h) if r["method"] in METHODS]
        for key, what in (("scalar_ratio", "compiled scalar loop (the paper's platform)"),
                          ("simd_ratio", "compiled SIMD build")):
            ranked = sorted((r for r in here if _finite(r[key])), key=lambda r: r[key])
            if not ranked:
                continue
            incr = first_row(here, method="incremental")
            spread = float(np.median([r[key.replace("ratio", "spread")] for r in ranked]))
            top = ", ".join(f"{_named(r, key)} ({_f(r['max_err_px'])} px)" for r in ranked[:5])
            ns = first_row(here, method="direct")[key.replace("ratio", "ns")]
            out.append(f"**Fastest as a {what}**, {int(h)} spans of {int(w)} pixels: {top}; `incremental` "
                       f"{_f(incr[key])}× ({_f(incr['max_err_px'])} px); `direct` takes {_f(ns)} ns per texel. "
                       f"Repeats spread by {_f(spread * 100, 2)} % (median interquartile range over median).")
        gpu = sorted((r for r in here if _finite(r["gpu_ratio"])), key=lambda r: r["gpu_ratio"])
        if gpu:
            hw = first_row(select_rows(rows, sweep="speed", span_length=w, spans=h), method="hardware")
            top = ", ".join(f"{_named(r, 'gpu_ratio')} ({_f(r['max_err_px'])} px)" for r in gpu[:4])
            out.append(f"**Fastest on the {gpu_label(software)}**, {int(h)} × {int(w)}: {top}; the rasteriser's whole pass "
                       f"{_f(hw['gpu_ratio'])}× (timer `{gpu[0]['timer']}`).")

    lengths = sorted({r["span_length"] for r in select_rows(rows, sweep="span_length")})
    incr = [_err(rows, "span_length", "incremental", span_length=n) for n in lengths]
    direct = [_err(rows, "span_length", "direct", span_length=n) for n in lengths]
    slope, offset, scatter = power_fit(lengths, incr)
    coord = max(_err(rows, "span_length", "incremental", "coord_max_texels", span_length=n) for n in lengths)
    text = (f"**Float32 incremental drift** (tilt {rows_tilt(rows)}°, a texel per pixel at the frame's middle, "
            f"coordinates up to {_f(coord)} texels): the worst pixel's error grows about as L^{_f(slope, 2)} "
            f"(least squares over {len(lengths)} span lengths from {int(lengths[0])} to {int(lengths[-1])}; single "
            f"lengths lie up to {_f(scatter, 2)}× off the fit, as the increment's low bits happen to round); "
            f"`direct` stays at {_f(min(direct))}–{_f(max(direct))} px at every length. By the fit the drift "
            f"reaches " + ", ".join(f"{b:g} px at L ≈ {_f(fitted_length(slope, offset, b))}"
                                      for b in DRIFT_BUDGETS) + ".")
    for n, name in ((1920, "1080p"), (3840, "4K")):
        if n in lengths:
            text += (f" At {n} pixels (a {name} row): {_f(_err(rows, 'span_length', 'incremental', span_length=n))}"
                     f" px ({_f(_err(rows, 'span_length', 'incremental', 'max_err', span_length=n))} texels).")
    out.append(text)

    longest = max(n for n in lengths if n <= 8192)
    base = _err(rows, "span_length", "incremental", span_length=longest)
    cuts = [f"`{m}` {_f(_err(rows, 'span_length', m, span_length=longest))} px "
            f"({_f(base / _err(rows, 'span_length', m, span_length=longest), 2)}× less)"
            for m in [*(f"parallel_{k}" for k in PARALLEL_THREADS), "two_ended"]]
    out.append(f"**k-parallel and two-ended stepping**, L = {int(longest)}: `incremental` {_f(base)} px; "
               f"{', '.join(cuts)}.")
    out.append(mitigation_answer(rows, longest))
    out.append(approximation_answer(rows))
    measured = [o for o in sorted({r["offset_texels"] for r in select_rows(rows, sweep="magnitude")})
                if _finite(_err(rows, "magnitude", "direct", offset_texels=o))]
    beyond = [o for o in {r["offset_texels"] for r in select_rows(rows, sweep="magnitude")} if o not in measured]
    if measured:
        top = measured[-1]
        parts = ", ".join(f"`{m}` {_f(_err(rows, 'magnitude', m, offset_texels=top))} px "
                          f"({_f(_err(rows, 'magnitude', m, 'max_err', offset_texels=top))} texels)"
                          for m in ("direct", "incremental", "kahan", "fixed16_16", "hardware"))
        out.append(f"**Large coordinates** (offset {top:g} texels, L = {int(suite.sweep_span)}): {parts}; "
                   f"float32's spacing there is {_f(float(np.spacing(np.float32(top))))} texels."
                   + (f" At offsets {', '.join(f'{o:g}' for o in sorted(beyond))} (beyond 2^23 texels) the span setup "
                      f"flags every pixel: no fractional bit is left." if beyond else ""))
    return out


def rows_tilt(rows) -> str:
    tilts = {r["tilt_deg"] for r in select_rows(rows, sweep="span_length")}
    return "/".join(f"{t:g}" for t in sorted(tilts))


def mitigation_answer(rows, length) -> str:
    base = _err(rows, "span_length", "incremental", span_length=length)
    target = 2 * _err(rows, "span_length", "direct", span_length=length)
    incr = speed_row(rows, "incremental")
    scored = []
    for m in MITIGATIONS:
        err = _err(rows, "span_length", m, span_length=length)
        t = speed_row(rows, m)
        if not (t and incr and err > 0 and _finite(t["scalar_ratio"])):
            continue
        scored.append((m, err, base / err, t["scalar_ratio"] / incr["scalar_ratio"],
                       t["simd_ratio"] / incr["simd_ratio"]))
    if not scored:
        return "**Mitigations**: not measured."
    parts = "; ".join(f"`{m}` {_f(err)} px ({_f(gain, 2)}× less, {_f(cost, 2)}× `incremental`'s scalar time, "
                      f"{_f(simd, 2)}× its SIMD time)" for m, err, gain, cost, simd in scored)
    enough = [s for s in scored if s[1] <= target]
    best = min(enough, key=lambda s: s[3], default=None)
    verdict = (f"The cheapest back to within 2× of `direct` ({_f(target)} px) as a scalar loop: `{best[0]}` "
               f"({_f(best[3], 2)}× `incremental`)." if best else
               f"None gets back to within 2× of `direct` ({_f(target)} px).")
    return f"**Mitigations** at L = {int(length)}, against `incremental` ({_f(base)} px): {parts}. {verdict}"


def approximation_answer(rows) -> str:
    tilts = sorted(t for t in {r["tilt_deg"] for r in select_rows(rows, sweep="tilt")} if t < 90)
    if not tilts:
        return "**Approximations**: not measured."
    top = tilts[-1]
    parts = []
    for name in APPROXIMATIONS:
        timing = speed_row(rows, name)
        parts.append(f"`{name}` {_f(_err(rows, 'tilt', name, tilt_deg=top))} px at {top:g}° "
                     f"({_f(_err(rows, 'tilt', name, 'exact_per_pixel', tilt_deg=top))} exact evaluations per pixel"
                     + (f"; {_f(timing['scalar_ratio'])}× `direct` scalar, {_f(timing['simd_ratio'])}× SIMD on the "
                        f"speed frame, where it errs {_f(timing['max_err_px'])} px" if timing else "") + ")")
    bounds = ", ".join(f"1/{e} px" for e in ADAPTIVE_FRACTIONS)
    return ("**Approximations** (linear between exact anchors; the error is the interpolation's): "
            + "; ".join(parts) + f". `adaptive_E` chooses each segment from the error bound of the chord of "
            f"u = w / q (docs/perspective.md) to stay within 1/E px ({bounds}).")


#: The report's title (harness.header).
TITLE = "Perspective-correct texturing: speed against float error (Romanyuk & Dudnyk)"

#: The plots (plots.py draws them), file name -> what it shows.
PLOTS = {
    "error_vs_span_length.png": "worst pixel's error against span length at a fixed footprint, screen pixels and "
                                "texels",
    "error_along_span.png": "where along the span the error builds up (screen pixels)",
    "error_vs_tilt.png": "worst pixel's error against the far-end angle, screen pixels and texels (90° and beyond: "
                         "drawn apart, their undefined pixels flagged)",
    "error_vs_magnitude.png": "worst pixel's error against texture-coordinate offset (heavy tiling)",
    "approximations.png": "subdivided against adaptive: error and exact evaluations per pixel against tilt",
    "pareto.png": "error against compiled CPU time (scalar, SIMD) and the GPU adapter's",
    "drift_heatmap.png": "where the incremental drift lands on a long grazing quad (screen pixels)",
    "tieback.png": "relief techniques' hit uv at large texture coordinates",
}


def sweep_section(rows, sweep: str, key: str, pixel_sets: list[list[str]], texels: list[str]) -> list[str]:
    """A sweep's tables: worst pixel's error in screen pixels for each set of methods, then in texels."""
    lines = ["Screen pixels:", ""]
    for methods in pixel_sets:
        lines += [*sweep_table(rows, sweep, key, methods), ""]
    return [*lines, "Texels:", "", *sweep_table(rows, sweep, key, texels, value="max_err")]


def _preamble(meta: dict) -> list[str]:
    """The header, the CPU, what a software adapter's times mean, and what the errors are."""
    lines = [
        *meta["header"].lines(),
        f"- CPU: {meta['cpu']} · Python {meta['python']}, numpy {meta['numpy']}, numba {meta['numba']} · "
        f"{meta['platform']}",
        "",
    ]
    if meta["software"]:
        lines += ["> The adapter is a **software** one: its \"GPU\" times are the kernels compiled for and run on the "
                  "CPU (SIMD lanes, a few cores). Read them as ratios measured side by side in one run; they say "
                  "nothing about a real GPU, where thread parallelism and memory behave differently. The compiled CPU "
                  "loops are the measurement of the paper's platform.", ""]
    lines += [
        "Errors are in **screen pixels**: the distance to the float64 evaluation of the same coefficients (texels) "
        "over the pixel's texel footprint, i.e. how far on screen the sample is off; texels beside them where the "
        "texture's scale matters. Every configuration's texel density gives its frame's middle pixel a footprint of "
        "one texel. Method, sweeps and caveats: `docs/perspective.md`.",
        "",
    ]
    return lines


def _loop_sections(rows: list[dict], suite) -> list[str]:
    """The compiled CPU loops, the operation counts, adaptive against fixed subdivision and the tile spans."""
    return [
        "## Compiled CPU loops (numba): the paper's platform",
        "",
        "Each method as a loop over spans and pixels in float32 (the IEEE operations of its numpy twin, bit for "
        "bit), timed per texel: a warm-up call, then repeats in which every method runs in turn (order rotated each "
        "repeat); the median over repeats, ± half the interquartile range over the median; `× direct` is the median "
        "of the ratios to `direct` in the same repeat. `scalar`: LLVM's vectorisers off, one pixel at a time; "
        "`SIMD`: on. `LLVM made` reads the SIMD build's optimised IR: `loop xN` (the loop vectoriser packed N "
        "pixels; the vector loop runs only where the loop has at least N iterations, e.g. k ≥ N lanes of "
        "`parallel_k`), `slp xN` (only a few independent operations packed), `scalar`.",
        "",
        *compiled_table(rows),
        "",
        "## Operation counts per texel (u and v together)",
        "",
        "Counted by running the numpy code with counting arithmetic (`arith.Arith`); the paper counts the shared "
        "denominator twice. `with FMA`: the same operations where each product feeding one addition becomes a fused "
        "multiply-add (the code's order; the arithmetic is never fused). `guard` is the WGSL kernels' compiler "
        "guard (a multiply by an opaque 1.0), absent from the compiled loops. A reciprocal 1/q counts as a division. "
        "`adaptive_E` counts on the speed frame, all its operations over its pixels (they depend on the "
        "geometry; the span setup's guards show here).",
        "",
        *operations_table(rows),
        "",
        f"## Adaptive subdivision against fixed subdivision (L = {suite.sweep_span})",
        "",
        "Worst pixel's error (screen pixels) and, in brackets, exact evaluations per pixel.",
        "",
        *adaptive_table(rows),
        "",
        f"## Spans of a tile or GPU rasteriser (worst pixel, screen pixels; {suite.sweep_span}-pixel rows cut into "
        "spans of the width, each from its own exact start)",
        "",
        *tile_table(rows),
        "",
    ]


def report_text(rows: list[dict], relief: list[dict], meta: dict, plotted: bool) -> str:
    suite = meta["suite"]
    speed = select_rows(rows, sweep="speed")
    timer = speed[0]["timer"] if speed else "–"
    gpu = gpu_label(meta["software"])
    lines = [
        *_preamble(meta),
        "## Recommendation",
        "",
        *recommendation(rows),
        "",
        "## Answers",
        "",
        *(f"- {a}" for a in answers(rows, suite, meta["software"])),
        "",
        "## Checks",
        "",
        *check_lines(rows),
        "",
        *_loop_sections(rows, suite),
        f"## Error against span length (worst pixel; tilt {rows_tilt(rows)}°, offset 0, a texel per pixel at the "
        "frame's middle)",
        "",
        *sweep_section(rows, "span_length", "span_length",
                       [PAPER_F32 + RECIPROCAL + APPROXIMATIONS + ["hardware"], ["incremental", *MITIGATIONS]],
                       ["direct", "incremental", "parallel_32", "two_ended", "subdivided_16", "adaptive_8", "kahan",
                        "hardware"]),
        "",
        f"## Error against tilt (worst pixel; L = {suite.sweep_span}; 90° = edge-on at the far end; beyond: past "
        "the horizon, those pixels flagged and left out)",
        "",
        *sweep_section(rows, "tilt", "tilt_deg", [PAPER_F32 + RECIPROCAL + APPROXIMATIONS + ["hardware"]],
                       ["direct", "incremental", "parallel_32", "two_ended", "subdivided_16", "adaptive_8", "kahan",
                        "hardware"]),
        "",
        "Flagged fraction per tilt (`direct`, `incremental`):",
        "",
        *sweep_table(rows, "tilt", "tilt_deg", ["direct", "incremental"], value="flagged_fraction"),
        "",
        f"## Error against texture-coordinate offset (worst pixel; L = {suite.sweep_span})",
        "",
        *sweep_section(rows, "magnitude", "offset_texels",
                       [PAPER_F32 + ["hardware"], ["incremental", *RECIPROCAL, *APPROXIMATIONS, *MITIGATIONS]],
                       ["direct", "incremental", "kahan", "fixed16_16", "hardware"]),
        "",
        f"## Timing on the {gpu}, and numpy's",
        "",
        f"The {gpu}: median time per pass over the run's rounds, every kernel's pass taking turns with the others "
        f"(timer `{timer}`; `wall-net` is submit to completion minus an empty pass, `docs/perspective.md` says why); "
        "± is half the interquartile range of the single passes over their median. numpy: median wall time of the "
        "numpy form (whole-array passes; Python loops for the Kahan, two-float and adaptive forms).",
        "",
        *gpu_table(rows, meta["software"]),
        "",
        "## The parallel forms on real threads",
        "",
        *threads_section(meta.get("threads", [])),
        "",
        "## Relief tie-back (p99 hit-uv error, texels; the entry uv rounded to float32 at that magnitude, the search "
        "on its fraction)",
        "",
        *tieback_table(relief),
        "",
        "## Plots",
        "",
        *((f"- `{name}`: {text}\n\n  ![{name}]({name})" for name, text in PLOTS.items()) if plotted else [MISSING]),
        "",
    ]
    return "\n".join(lines)
