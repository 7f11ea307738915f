"""report.md of a benchmark run (run.py): the headline per error budget, the thesis' Table 4.1 redone with error,
the per-height-map tables, map memory, which cost predicts the time, and the run's own figures."""

from __future__ import annotations

import math
from collections import defaultdict

import numpy as np

BUDGETS = (0.25, 0.5, 1.0)  # texels, p95 UV error
HEADLINE_MAX_ANGLE = 80.0  # the headline asks for the budget at every angle up to this
#: The configuration the headline's winner is compared with (the winner of the first H100 run).
REFERENCE_CONFIG = ("distance", "iterations=256")

#: Table 4.1 of the adaptive-POM thesis: FPS per angle for POM 4/8/16/24/32 layers and adaptive 4-32.
THESIS_ANGLES = (0.0, 45.0, 60.0, 80.0)
THESIS_LAYERS = (4, 8, 16, 24, 32)
THESIS_FPS = {
    0.0: (1294, 866, 418, 280, 207, 978),
    45.0: (571, 265, 121, 80, 62, 162),
    60.0: (670, 301, 150, 102, 76, 169),
    80.0: (1351, 735, 345, 247, 185, 332),
}
ADAPTIVE = "pom_adaptive"


def config_key(v: dict) -> tuple[str, str]:
    return v["technique"], v["params"]


def config_label(key) -> str:
    technique, params = key
    return technique if params == "-" else f"{technique} {params}"


def _f(x, digits=2) -> str:
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return "n/a"
    return f"{x:.{digits}f}"


def _geomean(xs) -> float:
    xs = [x for x in xs if x > 0 and math.isfinite(x)]
    return float(np.exp(np.mean(np.log(xs)))) if xs else float("nan")


def _layers(params: str) -> int | None:
    for part in params.split():
        if part.startswith("layers="):
            return int(part.split("=")[1])
    return None


# --- headline ---------------------------------------------------------------------------------

#: Configurations within this fraction of the headline winner's time are listed beside it.
CLOSE_MARGIN = 0.05


def headline(values: list[dict], max_angle: float = HEADLINE_MAX_ANGLE) -> list[dict]:
    """Per budget: the configuration with the lowest geometric-mean time ratio to basic among those
    whose p95 UV error is within the budget in every measurement (height map x angle <= max_angle)."""
    by_config = defaultdict(list)
    for v in values:
        if v["angle"] <= max_angle:
            by_config[config_key(v)].append(v)
    out = []
    for budget in BUDGETS:
        meeting = [{"budget": budget, "config": key, "ratio": _geomean(v["ratio_to_basic"] for v in vs),
                    "cases": len(vs), **cost_of(vs)}
                   for key, vs in by_config.items() if all(v["uv_err_p95"] <= budget for v in vs)]  # NaN fails
        if not meeting:
            out.append({"budget": budget, "config": None})
            continue
        meeting.sort(key=lambda m: m["ratio"])
        best = meeting[0]
        best["close"] = [m for m in meeting[1:] if m["ratio"] <= best["ratio"] * (1 + CLOSE_MARGIN)]
        out.append(best)
    return out


def cost_of(vs: list[dict]) -> dict:
    """Mean fetches, mean SIMD-tile fetches (NaN for runs without the column), worst p95 of some measurements."""
    simd = [v.get("fetches_simd", float("nan")) for v in vs]
    return {"fetches": float(np.mean([v["fetches_mean"] for v in vs])),
            "simd": float(np.mean(simd)) if all(math.isfinite(x) for x in simd) else float("nan"),
            "worst_p95": max(v["uv_err_p95"] for v in vs)}


def reference_cost(values: list[dict], max_angle: float = HEADLINE_MAX_ANGLE) -> dict | None:
    """REFERENCE_CONFIG's geometric-mean time ratio and costs over the headline's measurements (None if not run)."""
    vs = [v for v in values if config_key(v) == REFERENCE_CONFIG and v["angle"] <= max_angle]
    if not vs:
        return None
    return {"ratio": _geomean(v["ratio_to_basic"] for v in vs), **cost_of(vs)}


def pearson(x, y) -> float:
    x, y = np.asarray(x, np.float64), np.asarray(y, np.float64)
    if len(x) < 3 or x.std() == 0 or y.std() == 0:
        return float("nan")
    return float(np.corrcoef(x, y)[0, 1])


def cost_correlation(values: list[dict]) -> dict:
    """Pearson correlation over all rows of the time ratio to basic with mean fetches and with SIMD-tile fetches."""
    rows = [v for v in values if all(math.isfinite(v.get(k, float("nan")))
                                     for k in ("ratio_to_basic", "fetches_mean", "fetches_simd"))]
    ratio = [v["ratio_to_basic"] for v in rows]
    return {"rows": len(rows), "mean": pearson([v["fetches_mean"] for v in rows], ratio),
            "simd": pearson([v["fetches_simd"] for v in rows], ratio)}


def per_angle_budget(values: list[dict]) -> dict:
    """(budget, angle) -> (config, ratio) cheapest with p95 <= budget on every height map at that angle."""
    groups = defaultdict(lambda: defaultdict(list))
    for v in values:
        groups[v["angle"]][config_key(v)].append(v)
    out = {}
    for angle, configs in groups.items():
        for budget in BUDGETS:
            best = None
            for key, vs in configs.items():
                if all(v["uv_err_p95"] <= budget for v in vs):
                    ratio = _geomean(v["ratio_to_basic"] for v in vs)
                    if best is None or ratio < best[1]:
                        best = (key, ratio)
            out[budget, angle] = best
    return out


# --- Table 4.1 --------------------------------------------------------------------------------

def _thesis_configs(values):
    """POM rows of the thesis' layer counts and the adaptive rows, per (heightmap, angle)."""
    table = defaultdict(dict)
    for v in values:
        if v["angle"] not in THESIS_ANGLES:
            continue
        if v["technique"] == "pom" and _layers(v["params"]) in THESIS_LAYERS:
            table[v["heightmap"], v["angle"]][f"POM {_layers(v['params'])}"] = v
        elif v["technique"] == ADAPTIVE:
            table[v["heightmap"], v["angle"]].setdefault("adaptive", v)
    return table


def equal_error_speedups(values: list[dict]) -> list[dict]:
    """Per (heightmap, angle): adaptive POM against the cheapest POM setting (any layer count
    measured) whose p95 UV error is at most adaptive's."""
    adaptive = {(v["heightmap"], v["angle"]): v for v in values if v["technique"] == ADAPTIVE}
    pom = defaultdict(list)
    for v in values:
        if v["technique"] == "pom":
            pom[v["heightmap"], v["angle"]].append(v)
    out = []
    for key, a in sorted(adaptive.items()):
        matching = [p for p in pom[key] if p["uv_err_p95"] <= a["uv_err_p95"]]
        best = min(matching, key=lambda p: p["gpu_ms"]) if matching else None
        out.append({"heightmap": key[0], "angle": key[1], "adaptive": a, "pom": best,
                    "best_pom_p95": min((p["uv_err_p95"] for p in pom[key]), default=float("nan")),
                    "speedup": best["gpu_ms"] / a["gpu_ms"] if best and a["gpu_ms"] > 0 else float("nan")})
    return out


def table41_section(values: list[dict], registry_has_adaptive: bool) -> list[str]:
    lines = ["## The thesis' experiment (Table 4.1), redone with error", ""]
    head = "| angle | " + " | ".join(f"POM {n}" for n in THESIS_LAYERS) + " | adaptive 4–32 |"
    sep = "|---" * (len(THESIS_LAYERS) + 2) + "|"
    lines += ["Published (frames per second, jMonkeyEngine/OpenGL, the thesis' hardware and scene; "
              "no error was measured):", "", head, sep]
    for angle in THESIS_ANGLES:
        lines.append(f"| {angle:g}° | " + " | ".join(str(x) for x in THESIS_FPS[angle]) + " |")
    lines.append("| speed vs POM 4, mean | " + " | ".join(
        f"{np.mean([THESIS_FPS[a][i] / THESIS_FPS[a][0] for a in THESIS_ANGLES]):.2f}×"
        for i in range(len(THESIS_LAYERS) + 1)) + " |")
    lines.append("")
    if not registry_has_adaptive:
        lines += ["**Adaptive POM (`pom_adaptive`) is not in this build's technique registry**: the "
                  "measured tables list POM only; the benchmark picks adaptive POM up as soon as it is "
                  "registered.", ""]
    table = _thesis_configs(values)
    if not table:
        lines += ["(This run measured none of the thesis' configurations: it needs POM with 4–32 layers "
                  "at 0/45/60/80°.)", ""]
        return lines
    columns = [f"POM {n}" for n in THESIS_LAYERS] + (["adaptive"] if registry_has_adaptive else [])
    maps = sorted({k[0] for k in table}, key=lambda m: (m not in ("brick", "bricks"), m))
    for m in maps:
        lines += [f"Measured on **{m}**: GPU time as a multiple of basic texturing / speed relative to "
                  "POM 4 at the same angle / p95 UV error in texels:", "",
                  "| angle | " + " | ".join(columns) + " |", "|---" * (len(columns) + 1) + "|"]
        for angle in THESIS_ANGLES:
            cells = table.get((m, angle))
            if not cells:
                continue
            base = cells.get("POM 4")
            row = []
            for c in columns:
                v = cells.get(c)
                if v is None:
                    row.append("–")
                    continue
                rel = base["gpu_ms"] / v["gpu_ms"] if base and v["gpu_ms"] > 0 else float("nan")
                row.append(f"{_f(v['ratio_to_basic'])}× / {_f(rel)} / {_f(v['uv_err_p95'])}")
            lines.append(f"| {angle:g}° | " + " | ".join(row) + " |")
        lines.append("")
        # The thesis' "efficiency" figure recomputed on our times: mean FPS-equivalent of adaptive
        # against the mean of the POM columns with 4 and 8 layers at half weight.
        fps = {c: [1000.0 / table[m, a][c]["gpu_ms"] for a in THESIS_ANGLES
                   if (m, a) in table and c in table[m, a] and table[m, a][c]["gpu_ms"] > 0] for c in columns}
        if registry_has_adaptive and all(len(fps[c]) == len(THESIS_ANGLES) for c in columns):
            weights = [0.5, 0.5, 1, 1, 1]
            pom_mean = sum(w * np.mean(fps[f"POM {n}"]) for w, n in zip(weights, THESIS_LAYERS)) / sum(weights)
            lines += [f"The thesis' efficiency figure (mean FPS of adaptive vs the weighted mean of the POM "
                      f"columns, 4 and 8 layers at half weight; thesis: 410 vs 331, +24 %) on these times: "
                      f"{np.mean(fps['adaptive']):.0f} vs {pom_mean:.0f} frames/s-equivalent "
                      f"({(np.mean(fps['adaptive']) / pom_mean - 1) * 100:+.0f} %). It ignores error.", ""]
    speedups = equal_error_speedups(values)
    if speedups:
        lines += ["Speed-up of adaptive POM over the cheapest POM setting (any measured layer count) whose "
                  "p95 UV error is at most adaptive POM's (> 1: adaptive is faster at equal or better error):", "",
                  "| height map | angle | adaptive p95 (texels) | adaptive × basic | matching POM | its p95 | "
                  "its × basic | speed-up |", "|---|---|---|---|---|---|---|---|"]
        for s in speedups:
            a, p = s["adaptive"], s["pom"]
            if p is None:
                lines.append(f"| {s['heightmap']} | {s['angle']:g}° | {_f(a['uv_err_p95'])} | "
                             f"{_f(a['ratio_to_basic'])} | none measured (best POM p95 {_f(s['best_pom_p95'])}) "
                             f"| – | – | – |")
            else:
                lines.append(f"| {s['heightmap']} | {s['angle']:g}° | {_f(a['uv_err_p95'])} | "
                             f"{_f(a['ratio_to_basic'])} | POM {_layers(p['params'])} | {_f(p['uv_err_p95'])} | "
                             f"{_f(p['ratio_to_basic'])} | {_f(s['speedup'])}× |")
        finite = [s["speedup"] for s in speedups if math.isfinite(s["speedup"])]
        if finite:
            lines += ["", f"Geometric mean speed-up over the {len(finite)} cases with a matching POM setting: "
                      f"{_geomean(finite):.2f}× (range {min(finite):.2f}–{max(finite):.2f}×)."]
        lines.append("")
    return lines


# --- report -----------------------------------------------------------------------------------

def report(values: list[dict], meta: dict, plots: list[str], plot_note: str | None) -> str:
    from wgpuviewer.techniques import TECHNIQUES

    lines = [*_preamble(values, meta), *headline_section(values, meta)]
    lines += table41_section(values, "pom_adaptive" in TECHNIQUES)
    lines += per_heightmap_section(values)
    lines += memory_section(values) + correlation_section(values, meta) + run_section(meta)
    lines += ["## Plots", ""]
    if plot_note:
        lines.append(plot_note)
    for p in plots:
        lines.append(f"![{p}]({p})")
    lines.append("")
    return "\n".join(lines)


def _preamble(values: list[dict], meta: dict) -> list[str]:
    """The header, the run's settings, what the adapter's times mean, and where the method is."""
    suite = meta["suite"]
    w, h = suite.resolution
    lines = [
        *meta["header"].lines(),
        f"- backend: {meta['backend']}",
        f"- frame: {w}×{h}; timer: {meta['timer']} (median of {suite.frames} frames after {suite.warmup} "
        f"warm-up rounds, configurations interleaved frame by frame)",
        f"- height maps: {', '.join(dict.fromkeys(v['heightmap'] for v in values)) or 'none'}; "
        f"centre angles: {', '.join(f'{a:g}°' for a in suite.angles)}",
        f"- techniques: {', '.join(meta['techniques'])}; {len(meta['configs'])} configurations",
        f"- up to {suite.eval_pixels} pixels per measurement compared with the float64 reference"
        + (f"; python {meta['python']} on {meta['platform']}" if meta.get("python") else ""),
    ]
    if meta["software"]:
        lines.append("- **software adapter**: times are CPU times of an emulated GPU. Only the ratios to basic "
                     "(measured side by side) and the fetch counts say anything, and the ratios may differ on "
                     "real GPUs.")
    if "H100" in meta["adapter"] or "H200" in meta["adapter"]:
        lines.append("- **H100/H200**: graphics runs on 2 of their TPCs (4 of 132 SMs): fragment-shader times use about "
                     "3 % of the chip. The ratios between techniques are meaningful; the absolute milliseconds are not "
                     "those of a desktop GPU.")
    if meta["timer"] == "timestamp" and meta["busy_max"] > 1.05:
        lines.append(f"- **warning**: timed GPU intervals add up to {meta['busy_max']:.2f}× the wall time of "
                     "the run: the timestamp unit may not be nanoseconds on this adapter.")
    for note in meta["notes"]:
        lines.append(f"- note: {note}")
    lines += ["", "Method and definitions: docs/benchmarks.md. The angle is the view angle at the frame "
              "centre; it varies over the frame by up to about 1.5° (CSV: angle_min, angle_max). Rows with "
              "capped rays exclude them from the UV error; the capped fraction is listed beside it.", ""]
    return lines


def headline_section(values: list[dict], meta: dict) -> list[str]:
    """The cheapest configuration per error budget, near winners, the winners against the reference
    configuration, and the cheapest per angle."""
    suite = meta["suite"]
    lines = ["## Headline: cheapest technique per error budget", "",
              f"A configuration meets a budget when its p95 UV error is within it in every measurement up to "
              f"{HEADLINE_MAX_ANGLE:g}° (all height maps of this run); cost is the geometric mean of its time "
              "ratio to basic over those measurements.", "",
              "| p95 budget (texels) | cheapest | × basic | fetches/pixel (mean) | SIMD-tile fetches (mean) | worst p95 |",
              "|---|---|---|---|---|---|"]
    winners = headline(values)
    for hl in winners:
        if hl["config"] is None:
            lines.append(f"| ≤ {hl['budget']:g} | none of the measured configurations | – | – | – | – |")
        else:
            lines.append(f"| ≤ {hl['budget']:g} | {config_label(hl['config'])} | {_f(hl['ratio'])} | "
                         f"{_f(hl['fetches'], 1)} | {_f(hl['simd'], 1)} | {_f(hl['worst_p95'])} |")
    if meta["software"]:
        lines += ["", "**Software adapter: these time ratios are llvmpipe's (CPU time of an emulated GPU). The GPU "
                  "headline is still to be measured** (the full suite on a GPU, docs/benchmarks.md); the fetch counts "
                  "are the machine-independent part."]
    tw, th = suite.simd_tile
    lines += ["", f"SIMD-tile fetches: the mean over screen tiles of {tw}x{th} pixels of the tile's largest fetch "
              "count (what a SIMD group of that many lanes pays when its lanes loop until the slowest is done), "
              "averaged over the measurements."]
    close = [hl for hl in winners if hl.get("close")]
    if close:
        lines.append("")
        for hl in close:
            others = ", ".join(f"{config_label(m['config'])} {_f(m['ratio'])}× ({_f(m['simd'], 1)} SIMD-tile fetches)"
                               for m in hl["close"])
            lines.append(f"- ≤ {hl['budget']:g}: within {CLOSE_MARGIN:.0%} of the winner's time: {others}" +
                         (" — on a software adapter such a difference is within run-to-run noise." if meta["software"]
                          else "."))
    ref = reference_cost(values)
    if ref is not None:
        lines.append("")
        for hl in winners:
            if hl["config"] is not None and hl["config"] != REFERENCE_CONFIG:
                lines.append(f"- ≤ {hl['budget']:g}: {config_label(hl['config'])} takes {_f(hl['simd'] / ref['simd'], 3)}× the "
                             f"SIMD-tile fetches ({_f(hl['simd'], 1)} vs {_f(ref['simd'], 1)}) and "
                             f"{_f(hl['ratio'] / ref['ratio'])}× the time of {config_label(REFERENCE_CONFIG)} "
                             f"({_f(ref['ratio'])}× basic) over the same measurements.")
    angles = sorted({v["angle"] for v in values})
    pab = per_angle_budget(values)
    lines += ["", "Per angle (p95 within the budget on every height map at that angle):", "",
              "| budget | " + " | ".join(f"{a:g}°" for a in angles) + " |", "|---" * (len(angles) + 1) + "|"]
    for budget in BUDGETS:
        cells = []
        for a in angles:
            best = pab.get((budget, a))
            cells.append("none" if best is None else f"{config_label(best[0])} ({_f(best[1])}×)")
        lines.append(f"| ≤ {budget:g} | " + " | ".join(cells) + " |")
    lines.append("")
    return lines


def per_heightmap_section(values: list[dict]) -> list[str]:
    """Per height map and configuration: time ratio, fetches, capped share, PSNR and the p95 error per angle."""
    lines = ["## Per height map", "",
              "Time ratio to basic, fetches and SIMD-tile fetches: mean over the angles; then the p95 UV error (texels) "
              "per angle. "
              "All numbers per measurement are in results.csv.", ""]
    for m in dict.fromkeys(v["heightmap"] for v in values):
        vs = [v for v in values if v["heightmap"] == m]
        m_angles = sorted({v["angle"] for v in vs})
        lines += [f"### {m} ({vs[0]['heightmap_size']})", "",
                  "| configuration | × basic | fetches | SIMD-tile fetches | capped | min PSNR (dB) | " +
                  " | ".join(f"p95 {a:g}°" for a in m_angles) + " |", "|---" * (len(m_angles) + 6) + "|"]
        by_config = defaultdict(dict)
        for v in vs:
            by_config[config_key(v)][v["angle"]] = v
        for key, per_angle in by_config.items():
            rows = list(per_angle.values())
            lines.append(
                f"| {config_label(key)} | {_f(float(np.mean([r['ratio_to_basic'] for r in rows])))} | "
                f"{_f(float(np.mean([r['fetches_mean'] for r in rows])), 1)} | "
                f"{_f(float(np.mean([r['fetches_simd'] for r in rows])), 1)} | "
                f"{float(np.mean([r['capped_fraction'] for r in rows])):.1%} | "
                f"{_f(float(np.nanmin([r['psnr_db'] for r in rows])), 1)} | "
                + " | ".join(_f(per_angle[a]["uv_err_p95"]) if a in per_angle else "–" for a in m_angles) + " |")
        lines.append("")
    return lines


# --- map memory, cost model, the run ---------------------------------------------------------------

def _bytes(n: float) -> str:
    if not math.isfinite(n):
        return "n/a"
    for unit, size in (("MiB", 1 << 20), ("KiB", 1 << 10)):
        if n >= size:
            return f"{n / size:.1f} {unit}"
    return f"{n:.0f} B"


def memory_section(values: list[dict]) -> list[str]:
    """GPU memory of the height-derived maps each technique samples, per height map size."""
    sizes = list(dict.fromkeys(v["heightmap_size"] for v in values))
    table = defaultdict(dict)
    for v in values:
        size = v.get("map_bytes")  # None: a run from before the column
        table[v["technique"]][v["heightmap_size"]] = float("nan") if size is None else float(size)
    if all(not math.isfinite(b) for t in table.values() for b in t.values()):
        return []
    lines = ["## Map memory per technique", "",
             "GPU memory of the height-derived maps a technique samples (the depth map with its mip chain and the maps "
             "built from it; the material's albedo and normal map are not counted), per height map size:", "",
             "| technique | " + " | ".join(sizes) + " |", "|---" * (len(sizes) + 1) + "|"]
    for technique, per_size in table.items():
        lines.append(f"| {technique} | " + " | ".join(_bytes(per_size.get(s, float("nan"))) for s in sizes) + " |")
    return lines + [""]


def correlation_section(values: list[dict], meta: dict) -> list[str]:
    c = cost_correlation(values)
    if c["rows"] < 3 or not (math.isfinite(c["mean"]) and math.isfinite(c["simd"])):
        return []
    better = "SIMD-tile fetches" if c["simd"] > c["mean"] else "mean fetches"
    lines = ["## Which cost predicts the time", "",
             f"Pearson correlation over all {c['rows']} rows of the time ratio to basic with the mean fetches per "
             f"pixel: r = {c['mean']:.3f}; with the SIMD-tile fetches: r = {c['simd']:.3f}. **{better}** predict "
             "the time better on this adapter."]
    if meta.get("software"):
        lines.append("On a software adapter the times are CPU times of an emulated GPU: this says which cost predicts "
                     "llvmpipe, not a GPU. Run the full suite on a GPU for that.")
    per = per_fetch_time(values)
    if per:
        pom = per.get("pom")
        lines += ["", "Time per SIMD-tile fetch (median over the rows with at least one fetch of (time / basic - 1) / "
                  "SIMD-tile fetches)" + (", also in POM fetches (auto's COST_WEIGHTS come from this)" if pom else "")
                  + ":", "", "| technique | × basic per fetch |" + (" in POM fetches |" if pom else ""),
                  "|---|---|" + ("---|" if pom else "")]
        for technique, value in per.items():
            lines.append(f"| {technique} | {value:.3f} |" + (f" {value / pom:.2f} |" if pom else ""))
    return lines + [""]


def per_fetch_time(values: list[dict]) -> dict:
    """technique -> median over its rows with fetches of (ratio_to_basic - 1) / fetches_simd."""
    out = defaultdict(list)
    for v in values:
        simd = v.get("fetches_simd", float("nan"))
        if math.isfinite(simd) and simd >= 1 and math.isfinite(v["ratio_to_basic"]):
            out[v["technique"]].append((v["ratio_to_basic"] - 1.0) / simd)
    return {t: float(np.median(xs)) for t, xs in out.items()}


def run_section(meta: dict) -> list[str]:
    phases, counters = meta.get("phases"), meta.get("counters")
    if not phases or not counters:
        return []
    views = max(counters["views"], 1)
    return ["## The run", "",
            "Wall time per phase: " + ", ".join(f"{name} {seconds:.1f} s" for name, seconds in phases.items())
            + f". GPU work per view (all {len(meta['configs'])} configurations): "
            f"{counters['submits'] / views:.1f} submits and {counters['readbacks'] / views:.1f} read-backs "
            f"({counters['submits']} and {counters['readbacks']} in all, {counters['views']} views).", ""]
