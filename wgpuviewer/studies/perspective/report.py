"""``report.md`` and the plots of the perspective study, from its rows (``run.COLUMNS``). Every number in the
report is computed here from the measurements; nothing is typed in."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from wgpuviewer.core.io import atomic_open, write_bytes

from .methods import METHODS, PARALLEL_THREADS

PAPER_F32 = ["direct", "span", "incremental", *(f"parallel_{k}" for k in PARALLEL_THREADS), "two_ended"]
REFERENCE_F32 = [m.name for m in METHODS.values() if m.family == "reference"]
MITIGATIONS = [m.name for m in METHODS.values() if m.family == "mitigation"]
DRIFT_BUDGETS = (0.1, 0.5, 1.0)  # texels


def _f(x, digits: int = 3) -> str:
    if x == "" or x is None or (isinstance(x, float) and math.isnan(x)):
        return "–"
    if isinstance(x, float) and (x == 0 or 1e-3 <= abs(x) < 1e5):
        return f"{x:.{digits}g}"
    if isinstance(x, float):
        return f"{x:.{max(digits - 1, 1)}e}"
    return str(x)


def _first(rows, **match):
    for r in rows:
        if all(r.get(k) == v for k, v in match.items()):
            return r
    return None


def _select(rows, **match):
    return [r for r in rows if all(r.get(k) == v for k, v in match.items())]


def _f32(name: str) -> str:
    return "float32" if name == "hardware" else METHODS[name].precisions[0]


def _err(rows, sweep, method, key="max_err", **match):
    r = _first(rows, sweep=sweep, method=method, precision=_f32(method), **match)
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
    speed = _select(rows, sweep="speed")
    frames = list(dict.fromkeys((r["span_length"], r["spans"]) for r in speed))
    for w, h in frames:
        here = [r for r in speed if (r["span_length"], r["spans"]) == (w, h)]
        gpu = sorted((r for r in here if r["method"] in METHODS and isinstance(r["gpu_ratio"], float)),
                     key=lambda r: r["gpu_ratio"])
        cpu = sorted((r for r in here if r["method"] in METHODS and isinstance(r["cpu_ratio"], float)),
                     key=lambda r: r["cpu_ratio"])
        hw = _first(here, method="hardware")
        stepping = _first(here, method="incremental")
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

    lengths = sorted({r["span_length"] for r in _select(rows, sweep="span_length")})
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
    measured = [o for o in sorted({r["offset_texels"] for r in _select(rows, sweep="magnitude")})
                if math.isfinite(_err(rows, "magnitude", "direct", offset_texels=o))]
    beyond = [o for o in {r["offset_texels"] for r in _select(rows, sweep="magnitude")} if o not in measured]
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
    tilts = {r["tilt_deg"] for r in _select(rows, sweep="span_length")}
    return "/".join(f"{t:g}" for t in sorted(tilts))


def mitigation_answer(rows, length) -> str:
    base = _err(rows, "span_length", "incremental", span_length=length)
    target = 2 * _err(rows, "span_length", "direct", span_length=length)
    speed = _select(rows, sweep="speed")
    frame = (speed[0]["span_length"], speed[0]["spans"]) if speed else (None, None)
    t_incr = _first(speed, method="incremental", span_length=frame[0], spans=frame[1])
    scored = []
    for m in MITIGATIONS:
        err = _err(rows, "span_length", m, span_length=length)
        t = _first(speed, method=m, span_length=frame[0], spans=frame[1])
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
    points = sorted({r[key] for r in _select(rows, sweep=sweep)})
    header = [key, *(f"`{m}`" for m in methods)]
    body = [[p if key != "span_length" else str(int(p)), *(_err(rows, sweep, m, value, **{key: p}) for m in methods)]
            for p in points]
    return _table(header, body)


def speed_table(rows) -> list[str]:
    speed = _select(rows, sweep="speed")
    frames = list(dict.fromkeys((r["span_length"], r["spans"]) for r in speed))
    header = ["method", "precision", *(f"GPU × direct, {int(h)}×{int(w)} (spread)" for w, h in frames),
              "CPU × direct", "max error (texels)", "add", "mul", "div", "guard", "int add", "paper add/mul/div"]
    body = []
    for name in [*METHODS, "hardware"]:
        first = _first(speed, method=name, span_length=frames[0][0], spans=frames[0][1])
        if not first:
            continue
        ratios = []
        for w, h in frames:
            r = _first(speed, method=name, span_length=w, spans=h)
            ratios.append(f"{_f(r['gpu_ratio'])} (±{_f(r['gpu_spread'] * 50, 2)} %)" if r else "–")
        paper = f"{first['paper_adds']:g}/{first['paper_muls']:g}/{first['paper_divs']:g}" \
            if first["paper_adds"] != "" else "–"
        if name in METHODS and METHODS[name].paper_note:
            paper += f" ({METHODS[name].paper_note})"
        body.append([f"`{name}`", first["precision"], *ratios, first["cpu_ratio"], first["max_err"],
                     first["adds_per_texel"], first["muls_per_texel"], first["divs_per_texel"],
                     first["guards_per_texel"], first["int_adds_per_texel"], paper])
    return _table(header, body)


def check_lines(rows) -> list[str]:
    checked = [r for r in rows if r["gpu_max_ulp"] != ""]
    ulps = max((r["gpu_max_ulp"] for r in checked), default=float("nan"))
    flags = sum(r["gpu_flag_mismatch"] for r in checked)
    f64 = [r for r in rows if r["precision"] == "float64" and r["family"] == "paper" and r["tilt_deg"] < 90
           and isinstance(r["max_err"], float) and not math.isnan(r["max_err"])]
    ordinary = [r for r in f64 if r["span_length"] <= 1920 and r["tilt_deg"] <= 85 and r["offset_texels"] <= 1e3]
    worst = max(f64, key=lambda r: r["max_err"], default=None)
    undetected = sum(r["undetected"] for r in rows if r["undetected"] != "")
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
        row = [f"{m:g}", _first(relief, magnitude_uv=m)["input_spacing_texels"]]
        for t in techniques:
            for v in ("raw", "shader_fract"):
                r = _first(relief, technique=t, magnitude_uv=m, variant=v)
                row.append(r["p99_err"] if r else "")
        body.append(row)
    return _table(header, body)


# --- plots ------------------------------------------------------------------------------------------------------


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _save(fig, path: Path) -> None:
    with atomic_open(path) as f:
        fig.savefig(f, format="png", dpi=110, bbox_inches="tight")


def _style(name: str) -> dict:
    if name == "hardware":
        return {"color": "black", "linestyle": "-", "linewidth": 2.2, "marker": "s", "markersize": 4}
    family = METHODS[name].family
    return {"linestyle": {"paper": "-", "reference": ":", "mitigation": "--"}[family], "marker": "o", "markersize": 3}


VALUE_LABELS = {"max_err": "max texture-coordinate error (texels)",
                "max_err_px": "max error / the pixel's texel footprint (pixels)"}


def plot_sweep(plt, rows, sweep: str, key: str, path: Path, xlabel: str, logx: bool, title: str,
               values=("max_err",)) -> None:
    groups = [("the paper's forms (float32)", PAPER_F32 + ["hardware"]),
              ("subdivided and mitigations (float32)", ["incremental", *REFERENCE_F32, *MITIGATIONS])]
    fig, axes = plt.subplots(len(values), 2, figsize=(13, 4.8 * len(values)), sharey="row", squeeze=False)
    for line, value in zip(axes, values):
        for ax, (label, methods) in zip(line, groups):
            for m in methods:
                pts = sorted((r[key], r[value]) for r in _select(rows, sweep=sweep, method=m, precision=_f32(m))
                             if isinstance(r[value], float) and r[value] > 0)
                if pts:
                    ax.plot(*zip(*pts), label=m, **_style(m))
            ax.set_yscale("log")
            if logx:
                ax.set_xscale("log")
                if key == "span_length":  # label lengths people know (1080p and 4K rows), not powers of ten
                    from matplotlib.ticker import NullFormatter

                    lengths = {r[key] for r in _select(rows, sweep=sweep)}
                    marks = sorted(lengths & {64, 256, 1024, 1920, 3840, 8192, 16384}) or sorted(lengths)
                    ax.set_xticks(marks, [str(int(n)) for n in marks], fontsize=8)
                    ax.xaxis.set_minor_formatter(NullFormatter())
            ax.set_xlabel(xlabel)
            ax.set_title(label)
            ax.grid(True, which="both", alpha=0.3)
            ax.legend(fontsize=7, ncol=2)
        line[0].set_ylabel(VALUE_LABELS[value])
    fig.suptitle(title)
    _save(fig, path)
    plt.close(fig)


def plot_along(plt, along: list[dict], path: Path) -> None:
    fig, ax = plt.subplots(figsize=(8, 4.8))
    for m in ["incremental", "parallel_2", "parallel_8", "parallel_32", "two_ended", "direct", "kahan", "hardware"]:
        pts = [((r["n_start"] + r["n_end"]) / 2, r["max_err"]) for r in along
               if r["method"] == m and r["precision"] == _f32(m) and r["max_err"] > 0]
        if pts:
            ax.plot(*zip(*pts), label=m, **_style(m))
    ax.set_yscale("log")
    ax.set_xlabel("position along the span n (pixels)")
    ax.set_ylabel("max error in the bin (texels)")
    length = along[0]["span_length"] if along else 0
    ax.set_title(f"Where the float32 error builds up along a {int(length)}-pixel span")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    _save(fig, path)
    plt.close(fig)


def plot_pareto(plt, rows, path: Path) -> None:
    speed = _select(rows, sweep="speed")
    if not speed:
        return
    w, h = speed[0]["span_length"], speed[0]["spans"]
    here = [r for r in speed if (r["span_length"], r["spans"]) == (w, h)]
    fig, axes = plt.subplots(1, 2, figsize=(13, 5), sharey=True)
    for ax, key, label in ((axes[0], "gpu_ratio", "GPU time × direct"), (axes[1], "cpu_ratio", "CPU (numpy) time × direct")):
        for r in here:
            if not isinstance(r[key], float) or not r["max_err"] > 0:
                continue
            style = _style(r["method"])
            ax.scatter(r[key], r["max_err"], color=style.get("color"), marker=style["marker"], s=30)
            ax.annotate(r["method"], (r[key], r["max_err"]), fontsize=7, xytext=(3, 3), textcoords="offset points")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel(label)
        ax.grid(True, which="both", alpha=0.3)
    axes[0].set_ylabel("max error (texels)")
    fig.suptitle(f"Error against cost: {int(h)} spans of {int(w)} pixels, tilt {here[0]['tilt_deg']:g}°")
    _save(fig, path)
    plt.close(fig)


def plot_heatmap(plt, heat: dict, path: Path) -> None:
    from matplotlib.colors import LogNorm

    ref = heat["reference"]
    checker = (np.floor(ref.u / 32) + np.floor(ref.v / 32)) % 2
    picture = np.where(ref.valid, 0.35 + 0.5 * checker, 0.05)
    errors = [heat["incremental"], heat["direct"]]
    top = max(float(np.nanmax(e)) for e in errors)
    norm = LogNorm(vmin=max(top * 1e-5, 1e-6), vmax=top)
    fig, axes = plt.subplots(3, 1, figsize=(9, 11), layout="constrained")
    axes[0].imshow(picture, cmap="gray", vmin=0, vmax=1, interpolation="nearest")
    axes[0].set_title("the quad: a 32-texel checker at the float64 uv, unfiltered (black: past the horizon)")
    for ax, err, name in zip(axes[1:], errors, ("incremental", "direct")):
        image = ax.imshow(err, cmap="inferno", norm=norm, interpolation="nearest")
        ax.set_title(f"{name}, float32: texel error (max {np.nanmax(err):.3g}); each row is a span, left to right")
    fig.colorbar(image, ax=list(axes), label="texels (black: below the scale or not compared)", shrink=0.6)
    for ax in axes:
        ax.set_xticks([])
        ax.set_yticks([])
    s = heat["setup"]
    fig.suptitle(f"Float32 drift on a long grazing quad: {s.span_length}×{s.rows}, tilt {s.tilt:g}° at the far end")
    _save(fig, path)
    plt.close(fig)


def plot_tieback(plt, relief: list[dict], path: Path) -> None:
    if not relief:
        return
    fig, ax = plt.subplots(figsize=(8, 5))
    mags = sorted({r["magnitude_uv"] for r in relief if r["magnitude_uv"] > 0})
    for t in dict.fromkeys(r["technique"] for r in relief):
        for variant, style in (("raw", "-"), ("shader_fract", "--")):
            pts = [(r["magnitude_uv"], r["p99_err"]) for r in relief
                   if r["technique"] == t and r["variant"] == variant and r["magnitude_uv"] > 0]
            ax.plot(*zip(*sorted(pts)), style, marker="o", markersize=3, label=f"{t} ({variant})")
    spacing = [_first(relief, magnitude_uv=m)["input_spacing_texels"] for m in mags]
    ax.plot(mags, spacing, ":", color="black", label="float32 spacing of the uv")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("texture coordinate magnitude (UV units; the texture spans 1)")
    ax.set_ylabel("p99 hit-uv error (texels)")
    ax.set_title(f"Relief techniques at large uv ({int(relief[0]['texels'])}² map, {relief[0]['angle_deg']:g}°)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7)
    _save(fig, path)
    plt.close(fig)


PLOTS = {
    "error_vs_span_length.png": "max error against span length (tilt 80°)",
    "error_along_span.png": "where along the span the error builds up",
    "error_vs_tilt.png": "max error against the far-end angle (90°: edge-on), in texels and in pixels",
    "error_vs_magnitude.png": "max error against texture-coordinate offset (heavy tiling)",
    "pareto.png": "error against GPU and CPU cost",
    "drift_heatmap.png": "where the incremental drift lands on a long grazing quad",
    "tieback.png": "relief techniques' hit uv at large texture coordinates",
}


def write_outputs(out: Path, rows: list[dict], along: list[dict], relief: list[dict], heat: dict, meta: dict) -> None:
    plt = _pyplot()
    plot_sweep(plt, rows, "span_length", "span_length", out / "error_vs_span_length.png", "span length (pixels)",
               True, "Float32 error against span length")
    plot_along(plt, along, out / "error_along_span.png")
    plot_sweep(plt, rows, "tilt", "tilt_deg", out / "error_vs_tilt.png", "angle at the span's far end (degrees)",
               False, "Float32 error against tilt: in texels, and in pixels of the footprint there",
               values=("max_err", "max_err_px"))
    plot_sweep(plt, rows, "magnitude", "coord_max_texels", out / "error_vs_magnitude.png",
               "largest texture coordinate in the frame (texels)", True, "Float32 error against coordinate magnitude")
    plot_pareto(plt, rows, out / "pareto.png")
    plot_heatmap(plt, heat, out / "drift_heatmap.png")
    plot_tieback(plt, relief, out / "tieback.png")
    write_bytes(out / "report.md", report_text(rows, relief, meta).encode("utf-8"))


def report_text(rows: list[dict], relief: list[dict], meta: dict) -> str:
    suite = meta["suite"]
    lines = [
        "# Perspective-correct texturing: speed against float error (seed 001)",
        "",
        f"Command: `{meta['command'] or 'wgpuviewer perspective'}` · suite `{suite.name}` · {meta['date']}",
        f"Adapter: **{meta['adapter']}** · Python {meta['python']}, numpy {meta['numpy']} · {meta['platform']}",
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
        f"(timer `{_select(rows, sweep='speed')[0]['timer'] if _select(rows, sweep='speed') else '–'}`; "
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
        *(f"- `{name}`: {text}\n\n  ![{name}]({name})" for name, text in PLOTS.items()),
        "",
    ]
    return "\n".join(lines)

