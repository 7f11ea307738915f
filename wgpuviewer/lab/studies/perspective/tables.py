"""The perspective report's tables: error sweeps, compiled CPU loops, operation counts, the GPU's and numpy's
timing, adaptive against fixed subdivision, tile spans, the checks and the relief tie-back."""

from __future__ import annotations

from .methods import METHODS
from .selection import APPROXIMATIONS, _err, _f, _finite, first_row, select_rows, speed_frames, speed_row


def _table(header: list[str], body: list[list]) -> list[str]:
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(_f(c) if not isinstance(c, str) else c for c in row) + " |" for row in body]
    return lines


def _point(key: str, p) -> str:
    if key == "span_length":
        return str(int(p))
    if key == "tilt_deg" and p >= 90:
        return f"{p:g} (flagged beyond the horizon)"
    return _f(p) if isinstance(p, float) else str(p)


def sweep_table(rows, sweep: str, key: str, methods, value="max_err_px") -> list[str]:
    points = sorted({r[key] for r in select_rows(rows, sweep=sweep)})
    header = [key, *(f"`{m}`" for m in methods)]
    body = [[_point(key, p), *(_err(rows, sweep, m, value, **{key: p}) for m in methods)] for p in points]
    return _table(header, body)


def _timing(r, build: str) -> str:
    return f"{_f(r[f'{build}_ns'])} (±{_f(r[f'{build}_spread'] * 50, 2)} %)"


def compiled_table(rows) -> list[str]:
    frames = speed_frames(rows)
    if not frames:
        return ["Not measured."]
    w, h = frames[0]
    others = frames[1:]
    tiles = select_rows(rows, sweep="speed_tile")
    header = ["method", "scalar ns/texel", "scalar × direct", "SIMD ns/texel", "SIMD × direct", "LLVM made",
              *(f"scalar / SIMD × direct, {int(fh)}×{int(fw)}" for fw, fh in others),
              *([f"scalar / SIMD × direct, in {int(tiles[0]['span_length'])}-pixel spans"] if tiles else []),
              "max error (px)", "max error (texels)", "exact per pixel"]
    body = []
    for name in METHODS:
        r = speed_row(rows, name)
        if not r:
            continue
        extra = []
        for o in [speed_row(rows, name, frame) for frame in others] + ([first_row(tiles, method=name)] if tiles else []):
            extra.append(f"{_f(o['scalar_ratio'])} / {_f(o['simd_ratio'])}" if o else "–")
        body.append([f"`{name}`", _timing(r, "scalar"), r["scalar_ratio"], _timing(r, "simd"), r["simd_ratio"],
                     r["simd_vectorised"] or "–", *extra, r["max_err_px"], r["max_err"], r["exact_per_pixel"]])
    return [f"{int(h)} spans of {int(w)} pixels; the first precision of each method.", "", *_table(header, body)]


def operations_table(rows) -> list[str]:
    header = ["method", "paper add/mul/div", "code add/mul/div", "+ guard / int add / sqrt",
              "with FMA: add/mul/fma/div", "exact per pixel"]
    body = []
    for name, method in METHODS.items():
        r = speed_row(rows, name)
        if not r:
            continue
        paper = (f"{r['paper_adds']:g}/{r['paper_muls']:g}/{r['paper_divs']:g} ({method.paper_note})"
                 if r["paper_adds"] is not None else "–")
        body.append([f"`{name}`", paper,
                     f"{_f(r['adds_per_texel'])}/{_f(r['muls_per_texel'])}/{_f(r['divs_per_texel'])}",
                     f"{_f(r['guards_per_texel'])} / {_f(r['int_adds_per_texel'])} / {_f(r['sqrts_per_texel'])}",
                     f"{_f(r['fma_adds_per_texel'])}/{_f(r['fma_muls_per_texel'])}/{_f(r['fma_fmas_per_texel'])}/"
                     f"{_f(r['divs_per_texel'])}", r["exact_per_pixel"]])
    return _table(header, body)


def gpu_table(rows, software: bool) -> list[str]:
    frames = speed_frames(rows)
    label = "software GPU adapter" if software else "GPU"
    header = ["method", *(f"{label} × direct, {int(h)}×{int(w)} (spread)" for w, h in frames),
              *(f"numpy × direct, {int(h)}×{int(w)}" for w, h in frames)]
    body = []
    for name in [*METHODS, "hardware"]:
        cells = []
        for frame in frames:
            r = speed_row(rows, name, frame)
            cells.append(f"{_f(r['gpu_ratio'])} (±{_f(r['gpu_spread'] * 50, 2)} %)" if r and _finite(r["gpu_ratio"])
                         else "no kernel" if r else "–")
        for frame in frames:
            r = speed_row(rows, name, frame)
            cells.append(r["numpy_ratio"] if r and _finite(r["numpy_ratio"]) else "–")
        body.append([f"`{name}`", *cells])
    return _table(header, body)


def adaptive_table(rows) -> list[str]:
    tilts = sorted({r["tilt_deg"] for r in select_rows(rows, sweep="tilt")})
    header = ["tilt_deg", *(f"`{m}` px (exact/px)" for m in APPROXIMATIONS)]
    body = [[_point("tilt_deg", t), *(f"{_f(_err(rows, 'tilt', m, tilt_deg=t))} "
                                      f"({_f(_err(rows, 'tilt', m, 'exact_per_pixel', tilt_deg=t))})"
                                      for m in APPROXIMATIONS)] for t in tilts]
    return _table(header, body)


def tile_table(rows) -> list[str]:
    tiles = select_rows(rows, sweep="tile")
    if not tiles:
        return ["Not measured."]
    points = sorted({(r["tilt_deg"], r["span_length"]) for r in tiles})
    methods = ["direct", "incremental", "two_ended", "parallel_8", "kahan", *APPROXIMATIONS]
    body = [[f"{t:g}", str(int(w)), *(_err(rows, "tile", m, tilt_deg=t, span_length=w) for m in methods)]
            for t, w in points]
    return _table(["tilt_deg", "span width", *(f"`{m}`" for m in methods)], body)


def check_lines(rows) -> list[str]:
    gpu = [r for r in rows if r["gpu_max_ulp"] is not None]
    cpu = [r for r in rows if r["cpu_max_ulp"] is not None]
    f64 = [r for r in rows if r["precision"] == "float64" and r["family"] == "paper" and r["tilt_deg"] < 90
           and _finite(r["max_err"])]
    ordinary = [r for r in f64 if r["span_length"] <= 1920 and r["tilt_deg"] <= 85 and r["offset_texels"] <= 1e3]
    worst = max(f64, key=lambda r: r["max_err"], default=None)
    undetected = sum(r["undetected"] for r in rows if r["undetected"] is not None)
    return [
        f"- GPU kernels against their numpy twins, {len(gpu)} method × configuration checks: largest difference "
        f"{_f(float(max((r['gpu_max_ulp'] for r in gpu), default=float('nan'))))} ulp, "
        f"{int(sum(r['gpu_flag_mismatch'] for r in gpu))} flag mismatches (0 and 0: bit for bit).",
        f"- Compiled loops (scalar and SIMD builds) against their numpy twins, {len(cpu)} checks: largest difference "
        f"{_f(float(max((r['cpu_max_ulp'] for r in cpu), default=float('nan'))))} ulp, "
        f"{int(sum(r['cpu_flag_mismatch'] for r in cpu))} flag mismatches.",
        f"- Float64 forms of the paper's formulas against the float64 reference (`direct`): at most "
        f"{_f(max((r['max_err'] for r in ordinary), default=float('nan')))} texels on spans up to 1920 pixels, tilts "
        f"up to 85° and offsets up to 1000 texels; the worst before the horizon "
        + (f"{_f(worst['max_err'])} texels (`{worst['method']}`, L = {int(worst['span_length'])}, tilt "
           f"{worst['tilt_deg']:g}°, offset {worst['offset_texels']:g}; {_f(worst['max_err_px'])} px)." if worst
           else "–"),
        f"- Pixels whose texel is undefined (behind the eye, on the horizon, |uv| > 2^24) that some method did not "
        f"flag: {int(undetected)} over all rows.",
    ]


def tieback_table(relief: list[dict]) -> list[str]:
    mags = sorted({r["magnitude_uv"] for r in relief})
    techniques = list(dict.fromkeys(r["technique"] for r in relief))
    header = ["uv magnitude (UV units)", "float32 spacing (texels)", *(f"`{t}`" for t in techniques)]
    body = []
    for m in mags:
        row = [f"{m:g}", first_row(relief, magnitude_uv=m)["input_spacing_texels"]]
        for t in techniques:
            r = first_row(relief, technique=t, magnitude_uv=m)
            row.append(r["p99_err"] if r else "")
        body.append(row)
    return _table(header, body)
