"""``report.md`` of the perspective study, from its rows (``run.TABLE``); the plots are ``plots``. Every number in
the report is computed here from the measurements; nothing is typed in."""

from __future__ import annotations

import math

import numpy as np

from wgpuviewer.harness.plots import MISSING

from .methods import METHODS, PARALLEL_THREADS

PAPER_F32 = ["direct", "span", "incremental", *(f"parallel_{k}" for k in PARALLEL_THREADS), "two_ended"]
REFERENCE_F32 = [m.name for m in METHODS.values() if m.family == "reference"]
MITIGATIONS = [m.name for m in METHODS.values() if m.family == "mitigation"]
DRIFT_BUDGETS = (0.1, 0.5, 1.0)  # texels


def _f(x, digits: int = 3) -> str:
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return "–"
    if isinstance(x, float) and (x == 0 or 1e-3 <= abs(x) < 1e5):
        return f"{x:.{digits}g}"
    if isinstance(x, float):
        return f"{x:.{max(digits - 1, 1)}e}"
    return str(x)


def first_row(rows, **match):
    for r in rows:
        if all(r.get(k) == v for k, v in match.items()):
            return r
    return None


def select_rows(rows, **match):
    return [r for r in rows if all(r.get(k) == v for k, v in match.items())]


def single_precision(name: str) -> str:
    return "float32" if name == "hardware" else METHODS[name].precisions[0]


def _err(rows, sweep, method, key="max_err", **match):
    r = first_row(rows, sweep=sweep, method=method, precision=single_precision(method), **match)
    return r[key] if r else float("nan")


def power_fit(lengths, errors) -> tuple[float, float, float]:
    """Least-squares fit error ~ c L^p in log-log: (p, log c, the largest factor a point lies off the fit)."""
    pairs = [(math.log(n), math.log(e)) for n, e in zip(lengths, errors) if e > 0 and math.isfinite(e)]
    if len(pairs) < 2:
        return float("nan"), float("nan"), float("nan")
    x, y = np.array(pairs).T
    slope, offset = np.polyfit(x, y, 1)
    return float(slope), float(offset), float(np.exp(np.abs(y - (slope * x + offset)).max()))


def fitted_length(slope: float, offset: float, budget: float) -> float:
    """The span length where the fitted error reaches ``budget`` texels."""
    return math.exp((math.log(budget) - offset) / slope) if slope > 0 else float("nan")


# --- the answers ------------------------------------------------------------------------------------------------


def answers(rows: list[dict], suite) -> list[str]:
    out = []
    speed = select_rows(rows, sweep="speed")
    frames = list(dict.fromkeys((r["span_length"], r["spans"]) for r in speed))
    for w, h in frames:
        here = [r for r in speed if (r["span_length"], r["spans"]) == (w, h)]
        gpu = sorted((r for r in here if r["method"] in METHODS and isinstance(r["gpu_ratio"], float)),
                     key=lambda r: r["gpu_ratio"])
        cpu = sorted((r for r in here if r["method"] in METHODS and isinstance(r["cpu_ratio"], float)),
                     key=lambda r: r["cpu_ratio"])
        hw = first_row(here, method="hardware")
        stepping = first_row(here, method="incremental")
        if gpu:
            top = ", ".join(f"`{r['method']}` {_f(r['gpu_ratio'])}×" for r in gpu[:4])
            spread = float(np.median([r["gpu_spread"] for r in here]))
            out.append(f"**Fastest on the GPU**, {int(h)} spans of {int(w)} pixels: `{gpu[0]['method']}` "
                       f"({_f(gpu[0]['gpu_ratio'])}× `direct`'s time); the first four: {top}; `incremental` "
                       f"{_f(stepping['gpu_ratio'])}×; the rasteriser's whole pass {_f(hw['gpu_ratio'])}× "
                       f"(it also shades and writes a colour target). Single passes spread by {_f(spread * 100, 2)} % "
                       f"(median interquartile range over median, timer `{here[0]['timer']}`).")
        if cpu:
            top = ", ".join(f"`{r['method']}` {_f(r['cpu_ratio'])}×" for r in cpu[:4])
            out.append(f"**Fastest on the CPU (numpy)**, {int(h)} × {int(w)}: `{cpu[0]['method']}` "
                       f"({_f(cpu[0]['cpu_ratio'])}× `direct`); the first four: {top}; `incremental` "
                       f"{_f(stepping['cpu_ratio'])}×.")

    lengths = sorted({r["span_length"] for r in select_rows(rows, sweep="span_length")})
    incr = [_err(rows, "span_length", "incremental", span_length=n) for n in lengths]
    direct = [_err(rows, "span_length", "direct", span_length=n) for n in lengths]
    slope, offset, scatter = power_fit(lengths, incr)
    coord = max(_err(rows, "span_length", "incremental", "coord_max_texels", span_length=n) for n in lengths)
    text = (f"**Float32 incremental drift** (tilt {rows_tilt(rows)}°, coordinates up to {_f(coord)} texels): the max "
            f"error grows about as L^{_f(slope, 2)} (least squares over {len(lengths)} span lengths from "
            f"{int(lengths[0])} to {int(lengths[-1])}; single lengths lie up to {_f(scatter, 2)}× off the fit, "
            f"as the increment's low bits happen to round); `direct` stays at {_f(min(direct))}–{_f(max(direct))} "
            f"texels at every length. By the fit the drift reaches "
            + ", ".join(f"{b:g} texel at L ≈ {_f(fitted_length(slope, offset, b))}" for b in DRIFT_BUDGETS) + ".")
    for n, name in ((1920, "1080p"), (3840, "4K")):
        if n in lengths:
            err = _err(rows, "span_length", "incremental", span_length=n)
            px = _err(rows, "span_length", "incremental", "max_err_px", span_length=n)
            text += f" At {n} pixels (a {name} row): {_f(err)} texels, {_f(px)} of the pixel's footprint at worst."
    visible = [n for n in lengths if _err(rows, "span_length", "incremental", "max_err_px", span_length=n) >= 1.0]
    text += (f" It is a whole pixel's footprint or more (visible) from L = {int(visible[0])}." if visible else
             f" It stays under a pixel's footprint up to L = {int(lengths[-1])}.")
    out.append(text)

    longest = max(n for n in lengths if n <= 8192)
    base = _err(rows, "span_length", "incremental", span_length=longest)
    cuts = []
    for m in [*(f"parallel_{k}" for k in PARALLEL_THREADS), "two_ended"]:
        err = _err(rows, "span_length", m, span_length=longest)
        cuts.append(f"`{m}` {_f(err)} ({_f(base / err, 2)}× less)")
    out.append(f"**k-parallel and two-ended stepping**, L = {int(longest)}: `incremental` {_f(base)} texels; "
               f"{', '.join(cuts)}.")

    out.append(mitigation_answer(rows, longest))
    measured = [o for o in sorted({r["offset_texels"] for r in select_rows(rows, sweep="magnitude")})
                if math.isfinite(_err(rows, "magnitude", "direct", offset_texels=o))]
    beyond = [o for o in {r["offset_texels"] for r in select_rows(rows, sweep="magnitude")} if o not in measured]
    if measured:
        top = measured[-1]
        parts = ", ".join(f"`{m}` {_f(_err(rows, 'magnitude', m, offset_texels=top))}"
                          for m in ("direct", "incremental", "kahan", "fixed16_16", "hardware"))
        out.append(f"**Large coordinates** (offset {top:g} texels, L = {int(suite.sweep_span)}): max error {parts} texels; "
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
    speed = select_rows(rows, sweep="speed")
    frame = (speed[0]["span_length"], speed[0]["spans"]) if speed else (None, None)
    t_incr = first_row(speed, method="incremental", span_length=frame[0], spans=frame[1])
    scored = []
    for m in MITIGATIONS:
        err = _err(rows, "span_length", m, span_length=length)
        t = first_row(speed, method=m, span_length=frame[0], spans=frame[1])
        if not (t and t_incr and err > 0 and t_incr["gpu_ratio"] > 0):
            continue
        extra = sum(t[k] - t_incr[k] for k in ("adds_per_texel", "muls_per_texel", "guards_per_texel",
                                                "int_adds_per_texel", "divs_per_texel"))
        scored.append((m, err, base / err, t["gpu_ratio"] / t_incr["gpu_ratio"], extra))
    if not scored:
        return "**Mitigations**: not measured."
    parts = "; ".join(f"`{m}` {_f(err)} texels ({_f(gain, 2)}× less, {_f(cost, 2)}× the GPU time, "
                      f"{_f(extra, 2)} more ops per texel)" for m, err, gain, cost, extra in scored)
    enough = [s for s in scored if s[1] <= target]
    by_ops = min(enough, key=lambda s: s[4], default=None)
    by_time = min(enough, key=lambda s: s[3], default=None)
    verdict = (f"The cheapest back to within 2× of `direct` ({_f(target)} texels): by operations `{by_ops[0]}` "
               f"({_f(by_ops[4], 2)} more per texel), by GPU time here `{by_time[0]}` ({_f(by_time[3], 2)}×)."
               if enough else f"None gets back to within 2× of `direct` ({_f(target)} texels).")
    return f"**Mitigations** at L = {int(length)}, against `incremental` ({_f(base)} texels): {parts}. {verdict}"


# --- tables -----------------------------------------------------------------------------------------------------


def _table(header: list[str], body: list[list]) -> list[str]:
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(_f(c) if not isinstance(c, str) else c for c in row) + " |" for row in body]
    return lines


def sweep_table(rows, sweep: str, key: str, methods, value="max_err") -> list[str]:
    points = sorted({r[key] for r in select_rows(rows, sweep=sweep)})
    header = [key, *(f"`{m}`" for m in methods)]
    body = [[p if key != "span_length" else str(int(p)), *(_err(rows, sweep, m, value, **{key: p}) for m in methods)]
            for p in points]
    return _table(header, body)


def speed_table(rows) -> list[str]:
    speed = select_rows(rows, sweep="speed")
    frames = list(dict.fromkeys((r["span_length"], r["spans"]) for r in speed))
    header = ["method", "precision", *(f"GPU × direct, {int(h)}×{int(w)} (spread)" for w, h in frames),
              "CPU × direct", "max error (texels)", "add", "mul", "div", "guard", "int add", "paper add/mul/div"]
    body = []
    for name in [*METHODS, "hardware"]:
        first = first_row(speed, method=name, span_length=frames[0][0], spans=frames[0][1])
        if not first:
            continue
        ratios = []
        for w, h in frames:
            r = first_row(speed, method=name, span_length=w, spans=h)
            ratios.append(f"{_f(r['gpu_ratio'])} (±{_f(r['gpu_spread'] * 50, 2)} %)" if r else "–")
        paper = f"{first['paper_adds']:g}/{first['paper_muls']:g}/{first['paper_divs']:g}" \
            if first["paper_adds"] is not None else "–"
        if name in METHODS and METHODS[name].paper_note:
            paper += f" ({METHODS[name].paper_note})"
        body.append([f"`{name}`", first["precision"], *ratios, first["cpu_ratio"], first["max_err"],
                     first["adds_per_texel"], first["muls_per_texel"], first["divs_per_texel"],
                     first["guards_per_texel"], first["int_adds_per_texel"], paper])
    return _table(header, body)


def check_lines(rows) -> list[str]:
    checked = [r for r in rows if r["gpu_max_ulp"] is not None]
    ulps = max((r["gpu_max_ulp"] for r in checked), default=float("nan"))
    flags = sum(r["gpu_flag_mismatch"] for r in checked)
    f64 = [r for r in rows if r["precision"] == "float64" and r["family"] == "paper" and r["tilt_deg"] < 90
           and isinstance(r["max_err"], float) and not math.isnan(r["max_err"])]
    ordinary = [r for r in f64 if r["span_length"] <= 1920 and r["tilt_deg"] <= 85 and r["offset_texels"] <= 1e3]
    worst = max(f64, key=lambda r: r["max_err"], default=None)
    undetected = sum(r["undetected"] for r in rows if r["undetected"] is not None)
    return [
        f"- GPU kernels against their numpy twins, {len(checked)} method × configuration checks: largest difference "
        f"{_f(float(ulps))} ulp, {int(flags)} flag mismatches (0 and 0: bit for bit).",
        f"- Float64 forms of the paper's formulas against the float64 reference (`direct`): at most "
        f"{_f(max((r['max_err'] for r in ordinary), default=float('nan')))} texels on spans up to 1920 pixels, tilts "
        f"up to 85° and offsets up to 1000 texels; the worst before the horizon "
        + (f"{_f(worst['max_err'])} texels (`{worst['method']}`, L = {int(worst['span_length'])}, tilt "
           f"{worst['tilt_deg']:g}°, offset {worst['offset_texels']:g}; {_f(worst['max_err_px'])} of a pixel's "
           f"footprint): float64 drifts by the same law as float32, 2^29 times less." if worst else "–"),
        f"- Pixels whose texel is undefined (behind the eye, on the horizon, |uv| > 2^24) that some method did not "
        f"flag: {int(undetected)} over all rows.",
    ]


def tieback_table(relief: list[dict]) -> list[str]:
    mags = sorted({r["magnitude_uv"] for r in relief})
    techniques = list(dict.fromkeys(r["technique"] for r in relief))
    header = ["uv magnitude (UV units)", "float32 spacing (texels)",
              *(f"`{t}` {v}" for t in techniques for v in ("raw", "fract"))]
    body = []
    for m in mags:
        row = [f"{m:g}", first_row(relief, magnitude_uv=m)["input_spacing_texels"]]
        for t in techniques:
            for v in ("raw", "shader_fract"):
                r = first_row(relief, technique=t, magnitude_uv=m, variant=v)
                row.append(r["p99_err"] if r else "")
        body.append(row)
    return _table(header, body)


#: The report's title (harness.header).
TITLE = "Perspective-correct texturing: speed against float error (Romanyuk & Dudnyk)"

#: The plots (plots.py draws them), file name -> what it shows.
PLOTS = {
    "error_vs_span_length.png": "max error against span length (tilt 80°)",
    "error_along_span.png": "where along the span the error builds up",
    "error_vs_tilt.png": "max error against the far-end angle (90°: edge-on), in texels and in pixels",
    "error_vs_magnitude.png": "max error against texture-coordinate offset (heavy tiling)",
    "pareto.png": "error against GPU and CPU cost",
    "drift_heatmap.png": "where the incremental drift lands on a long grazing quad",
    "tieback.png": "relief techniques' hit uv at large texture coordinates",
}


def report_text(rows: list[dict], relief: list[dict], meta: dict, plotted: bool) -> str:
    suite = meta["suite"]
    lines = [
        *meta["header"].lines(),
        f"- Python {meta['python']}, numpy {meta['numpy']} · {meta['platform']}",
        "",
    ]
    if meta["software"]:
        lines += ["> The adapter is a **software** one: its \"GPU\" times are the kernels compiled for and run on the "
                  "CPU (SIMD lanes, a few cores). Read them as ratios measured side by side in one run; they say "
                  "nothing absolute about a real GPU, where thread parallelism and memory behave differently.", ""]
    lines += [
        "Texture coordinates are in texels; error = Euclidean distance to the float64 evaluation of the same "
        "coefficients. `max_err_px` is the error divided by the pixel's texel footprint (how far on screen the "
        "texel is off). Method, sweeps and caveats: `docs/perspective.md`.",
        "",
        "## Answers",
        "",
        *(f"- {a}" for a in answers(rows, suite)),
        "",
        "## Checks",
        "",
        *check_lines(rows),
        "",
        f"## Error against span length (max, texels; tilt {rows_tilt(rows)}°, offset 0)",
        "",
        *sweep_table(rows, "span_length", "span_length", PAPER_F32 + REFERENCE_F32 + ["hardware"]),
        "",
        *sweep_table(rows, "span_length", "span_length", ["incremental", *MITIGATIONS]),
        "",
        f"## Error against tilt (max, texels; L = {suite.sweep_span}; 90° = edge-on at the far end, beyond: past "
        "the horizon, those pixels flagged)",
        "",
        *sweep_table(rows, "tilt", "tilt_deg", PAPER_F32 + REFERENCE_F32 + ["hardware"]),
        "",
        "The same as a fraction of the pixel's footprint (`max_err_px`):",
        "",
        *sweep_table(rows, "tilt", "tilt_deg", ["direct", "incremental", "parallel_32", "two_ended", "subdivided_16",
                                                "kahan", "hardware"], value="max_err_px"),
        "",
        "Flagged fraction per tilt (`direct`, `incremental`):",
        "",
        *sweep_table(rows, "tilt", "tilt_deg", ["direct", "incremental"], value="flagged_fraction"),
        "",
        f"## Error against texture-coordinate offset (max, texels; L = {suite.sweep_span})",
        "",
        *sweep_table(rows, "magnitude", "offset_texels", PAPER_F32 + ["hardware"]),
        "",
        *sweep_table(rows, "magnitude", "offset_texels", ["incremental", *REFERENCE_F32, *MITIGATIONS]),
        "",
        "## Speed and operation counts",
        "",
        "GPU: median time per pass over the run's rounds, every method's pass taking turns with the others "
        f"(timer `{select_rows(rows, sweep='speed')[0]['timer'] if select_rows(rows, sweep='speed') else '–'}`; "
        "`wall-net` is submit to completion minus an empty pass, `docs/perspective.md` says why); ± is half the "
        "interquartile range of the single passes over their median. CPU: median wall time of the numpy form. "
        "Operation counts per texel (u and v together) come from running the numpy code with counting "
        "arithmetic; `guard` is the compiler guard (a multiply by an opaque 1.0). The paper counts the shared "
        "denominator twice.",
        "",
        *speed_table(rows),
        "",
        "## Relief tie-back (p99 hit-uv error, texels; `raw`: the float32 entry uv at that magnitude, `fract`: "
        "wrapped to [0, 1) in float32 first)",
        "",
        *tieback_table(relief),
        "",
        "## Plots",
        "",
        *((f"- `{name}`: {text}\n\n  ![{name}]({name})" for name, text in PLOTS.items()) if plotted else [MISSING]),
        "",
    ]
    return "\n".join(lines)

