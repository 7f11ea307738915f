"""The filtering study's outputs: ``results.csv`` (one row per case x configuration, ``suites.TABLE``),
``report.md`` (the answer to the filtering paper's question with the numbers behind it), ``pareto.png`` (error
against GPU time) and side-by-side crops (``crops_CASE.png``: reference and filters, with their difference
images)."""

from __future__ import annotations

import math
from collections import defaultdict
from pathlib import Path

import numpy as np

from wgpuviewer.core.errors import UserError
from wgpuviewer.core.io import write_bytes
from wgpuviewer.harness.header import Header
from wgpuviewer.harness.plots import pyplot, save_png

from .suites import BASELINE, TABLE, Config, Options, Suite
from .views import ALBEDOS, HEIGHT_SCALE, RELIEFS, TECHNIQUE, Case

#: The crops' panels: the reference, then these configurations (label, Config), then their difference images.
CROP_PANELS = (
    ("trilinear", Config("trilinear", "uv")),
    ("aniso 16", Config("aniso", "uv", (("max_anisotropy", 16),))),
    ("ewa", Config("ewa", "displaced")),
    ("ewa_vis", Config("ewa_vis", "displaced")),
    ("ewa_vis_rows", Config("ewa_vis_rows", "displaced")),
)
DIFF_GAIN = 4.0  # difference images: |filter - reference| x this
CROP = (40, 30)  # crop size, pixels (the window with the most occluded pixels)
ZOOM = 4


def wanted_for_pictures(case: Case, suite: Suite) -> bool:
    """Crops for the occluding cases with the relief's own albedo (the visibility question) and the checker, at the
    suite's steepest angle up to 80 degrees, and the relief's smallest minification there."""
    angles = [c.angle for c in suite.cases if c.angle <= 80.0] or [c.angle for c in suite.cases]
    footprints = [c.footprint for c in suite.cases if c.relief == case.relief and c.angle == case.angle]
    return (case.occluding and case.albedo in ("own", "checker") and case.angle == max(angles)
            and case.footprint == min(footprints))


TITLE = "Texture filtering on relief surfaces (Romanyuk & Dudnyk 2017)"


def write(out: Path, rows: list[dict], kept: list, options: Options, header: Header) -> None:
    TABLE.write(out / "results.csv", rows)
    pictures = [write_crops(out, result) for result in kept]
    pareto = write_pareto(out / "pareto.png", rows)
    write_bytes(out / "report.md", markdown(rows, options, header, pictures, pareto).encode())


# --- aggregation ---------------------------------------------------------------------------------------------


def _mean(values) -> float:
    values = [v for v in values if isinstance(v, float) and math.isfinite(v)]
    return float(np.mean(values)) if values else float("nan")


def _geomean(values) -> float:
    values = [v for v in values if isinstance(v, float) and math.isfinite(v) and v > 0]
    return float(np.exp(np.mean(np.log(values)))) if values else float("nan")


def by_config(rows: list[dict]) -> dict[str, list[dict]]:
    groups = defaultdict(list)
    for row in rows:
        groups[row["label"]].append(row)
    return groups


def gain(rows: list[dict], a: str, b: str, key: str) -> tuple[float, int]:
    """Mean over cases of row[key](label a) - row[key](label b), and how many cases had both."""
    per_case = defaultdict(dict)
    for row in rows:
        per_case[row["case"]][row["label"]] = row[key]
    diffs = [c[a] - c[b] for c in per_case.values() if a in c and b in c
             and math.isfinite(c[a]) and math.isfinite(c[b])]
    return (float(np.mean(diffs)) if diffs else float("nan")), len(diffs)


def _label(filter_name: str, source: str, params: str = "") -> str:
    return f"{filter_name}{' ' + params if params else ''} ({source})"


# --- pictures ------------------------------------------------------------------------------------------------


def _crop_window(mask: np.ndarray, size: tuple[int, int]) -> tuple[int, int]:
    """(y, x) of the size window with the most True pixels (the first one on ties)."""
    w, h = min(size[0], mask.shape[1]), min(size[1], mask.shape[0])
    s = np.pad(np.cumsum(np.cumsum(mask.astype(np.int64), 0), 1), ((1, 0), (1, 0)))
    counts = s[h:, w:] - s[:-h, w:] - s[h:, :-w] + s[:-h, :-w]
    y, x = np.unravel_index(int(np.argmax(counts)), counts.shape)
    return int(y), int(x)


def write_crops(out: Path, result) -> str:
    import cv2

    ref = result.reference
    y, x = _crop_window(ref.occluded, CROP)
    h, w = min(CROP[1], ref.color.shape[0]), min(CROP[0], ref.color.shape[1])

    def crop(image):
        return np.clip(image[y:y + h, x:x + w], 0.0, 1.0)

    panels = [("reference", crop(ref.color))]
    diffs = [("occluded pixels", np.repeat(crop(ref.occluded.astype(np.float64))[..., None], 3, axis=2))]
    for label, config in CROP_PANELS:
        image = result.images.get(config)
        if image is None:
            continue
        panels.append((label, crop(image)))
        diffs.append((f"|{label} - ref| x{DIFF_GAIN:g}", np.clip(np.abs(crop(image) - crop(ref.color)) * DIFF_GAIN, 0, 1)))

    def strip(items):
        tiles = []
        for label, image in items:
            big = cv2.resize((image * 255).round().astype(np.uint8), (w * ZOOM, h * ZOOM),
                             interpolation=cv2.INTER_NEAREST)
            header = np.full((18, w * ZOOM, 3), 255, np.uint8)
            cv2.putText(header, label, (3, 13), cv2.FONT_HERSHEY_SIMPLEX, 0.42, (0, 0, 0), 1, cv2.LINE_AA)
            tiles.append(np.concatenate([header, big], 0))
            tiles.append(np.full((tiles[-1].shape[0], 4, 3), 255, np.uint8))
        return np.concatenate(tiles[:-1], 1)

    top, bottom = strip(panels), strip(diffs)
    width = max(top.shape[1], bottom.shape[1])
    rows = [np.pad(t, ((0, 0), (0, width - t.shape[1]), (0, 0)), constant_values=255) for t in (top, bottom)]
    picture = np.concatenate([rows[0], np.full((6, width, 3), 255, np.uint8), rows[1]], 0)
    name = f"crops_{result.case.name}.png"
    ok, encoded = cv2.imencode(".png", cv2.cvtColor(picture, cv2.COLOR_RGB2BGR))
    if not ok:
        raise UserError(f"{out / name}: could not encode the PNG")
    write_bytes(out / name, encoded.tobytes())
    return name


def write_pareto(path: Path, rows: list[dict]) -> str | None:
    """PSNR (mean over occluding cases, and over flat ones) against the time ratio, one point per configuration;
    None without matplotlib."""
    with pyplot() as plt:
        return None if plt is None else _draw_pareto(plt, path, rows)


def _draw_pareto(plt, path: Path, rows: list[dict]) -> str:
    fig, axes = plt.subplots(1, 2, figsize=(12, 5), sharey=False)
    for ax, occluding in zip(axes, (True, False)):
        subset = [r for r in rows if r["occluding"] == occluding]
        points = []
        for label, group in by_config(subset).items():
            t, p = _geomean([r["time_ratio"] for r in group]), _mean([r["psnr"] for r in group])
            if math.isfinite(t) and math.isfinite(p):
                points.append((t, p, label))
        for t, p, label in points:
            colour = "tab:red" if "vis" in label else ("tab:blue" if "ewa" in label else "tab:grey")
            ax.scatter(t, p, color=colour, s=18)
            ax.annotate(label, (t, p), fontsize=6, xytext=(3, 2), textcoords="offset points")
        front = sorted(points)
        best, line = -math.inf, []
        for t, p, _ in front:
            if p > best:
                best = p
                line.append((t, p))
        if line:
            ax.plot(*zip(*line), color="black", linewidth=0.8, linestyle="--", label="Pareto front")
            ax.legend(fontsize=7)
        ax.set_xscale("log")
        ax.set_xlabel("GPU time / trilinear (same run, geometric mean)")
        ax.set_ylabel("PSNR against the box reference, dB (mean)")
        ax.set_title("relief with occlusion" if occluding else "flat relief")
        ax.grid(True, which="both")
    fig.tight_layout()
    return save_png(fig, path, dpi=120, tight=False)


# --- report.md -------------------------------------------------------------------------------------------------


def _table(rows: list[dict]) -> list[str]:
    lines = ["| filter (derivatives) | PSNR dB | SSIM | PSNR vs Gaussian ref | PSNR occluded px | time x trilinear | "
             "texels/px | depth fetches/px | hidden texels/px | capped |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for label, group in sorted(by_config(rows).items(), key=lambda kv: -_mean([r["psnr"] for r in kv[1]])):
        lines.append(
            f"| {label} | {_mean([r['psnr'] for r in group]):.2f} | {_mean([r['ssim'] for r in group]):.3f} | "
            f"{_mean([r['psnr_gauss'] for r in group]):.2f} | {_mean([r['psnr_occluded'] for r in group]):.2f} | "
            f"{_geomean([r['time_ratio'] for r in group]):.2f} | {_mean([r['texels_per_pixel'] for r in group]):.1f} | "
            f"{_mean([r['depth_fetches_per_pixel'] for r in group]):.0f} | "
            f"{_mean([r['hidden_per_pixel'] for r in group]):.2f} | {_mean([r['capped_share'] for r in group]):.1%} |")
    return lines


def answer(rows: list[dict]) -> list[str]:
    """The paper's question, answered from the rows: on occluding reliefs, what visibility-aware EWA changes."""
    occl = [r for r in rows if r["occluding"]]
    if not occl:
        return ["No case with occlusion was measured."]
    lines = []
    groups = {"relief's own albedo (colour follows height)": [r for r in occl if r["albedo"] == "own"],
              "albedo independent of the relief": [r for r in occl if r["albedo"] != "own"],
              "all occluding cases": occl}
    trilinear, aniso = _label("trilinear", "uv"), _label("aniso", "uv", "16")
    lines.append("Mean PSNR change (dB, all covered pixels / occluded pixels only) of the visibility filters, per "
                 "derivative source, over the cases of each group; time is the geometric mean ratio to trilinear:")
    lines.append("")
    lines.append("| group | filter | vs ewa, same source | vs aniso 16 (uv) | vs trilinear (uv) | time x trilinear | "
                 "time x ewa | cases |")
    lines.append("|---|---|---|---|---|---|---|---|")
    for title, subset in groups.items():
        if not subset:
            continue
        for vis in ("ewa_vis", "ewa_vis_rows"):
            for source in ("displaced", "analytic", "uv"):
                label, plain = _label(vis, source), _label("ewa", source)
                if not any(r["label"] == label for r in subset):
                    continue
                cells = []
                for other in (plain, aniso, trilinear):
                    g, n = gain(subset, label, other, "psnr")
                    go, _ = gain(subset, label, other, "psnr_occluded")
                    cells.append(f"{g:+.2f} / {go:+.2f}" if n else "–")
                t = _geomean([r["time_ratio"] for r in subset if r["label"] == label])
                te = t / _geomean([r["time_ratio"] for r in subset if r["label"] == plain])
                n = sum(1 for r in subset if r["label"] == label)
                lines.append(f"| {title} | {label} | {' | '.join(cells)} | {t:.1f} | {te:.1f} | {n} |")
    lines.append("")
    full, _ = gain(occl, _label("ewa_vis", "displaced"), _label("ewa", "displaced"), "psnr")
    rows_gain, _ = gain(occl, _label("ewa_vis_rows", "displaced"), _label("ewa", "displaced"), "psnr")
    t_full = _geomean([r["depth_fetches_per_pixel"] for r in occl if r["label"] == _label("ewa_vis", "displaced")])
    t_rows = _geomean([r["depth_fetches_per_pixel"] for r in occl if r["label"] == _label("ewa_vis_rows", "displaced")])
    if math.isfinite(full) and math.isfinite(rows_gain):
        lines.append(f"Row-ends method (displaced): {rows_gain:+.2f} dB against the full method's {full:+.2f} dB over "
                     f"plain EWA, with {t_rows / t_full:.0%} of its visibility-trace fetches.")
    return lines


def _delta(psnrs: dict, a: str, b: str) -> str:
    return f"{psnrs[a] - psnrs[b]:+.2f}" if a in psnrs and b in psnrs else "–"


def markdown(rows: list[dict], options: Options, header: Header, pictures: list[str], pareto: str | None) -> str:
    suite = options.suite
    timer = rows[0]["timer"] if rows else "?"
    software = any(word in header.adapter.lower() for word in ("llvmpipe", "lavapipe", "swiftshader", "warp"))
    lines = [
        *header.lines(),
        f"- timer: {timer}" + (" — a CPU-emulated adapter: GPU times are ratios measured side by side in one run, "
                               "not real-GPU speeds" if software else ""),
        f"- {len(suite.cases)} cases x {len(suite.configs)} configurations, frames {suite.size[0]}x{suite.size[1]}, "
        f"reference {suite.reference}x{suite.reference} rays per pixel, {suite.frames} timed frames each (median)",
        "",
        f"Technique `{TECHNIQUE}` (exact hits) for every render; relief depth {HEIGHT_SCALE} UV units per tile; "
        "errors of the unlit, filtered albedo against the supersampled reference (method: docs/filtering.md).", "",
        "## The answer", "", *answer(rows), "",
    ]
    if pareto:
        lines += [f"![error against time]({pareto})", ""]
    for picture in pictures:
        lines += [f"![crops]({picture})", ""]
    for title, subset in (("Relief with occlusion", [r for r in rows if r["occluding"]]),
                          ("Flat relief", [r for r in rows if not r["occluding"]])):
        if subset:
            lines += [f"## {title} ({len({r['case'] for r in subset})} cases)", "", *_table(subset), ""]
    lines += ["## Per case", "", "Visibility's effect per case: PSNR of ewa_vis minus that of ewa on the same "
              "derivative source (displaced / analytic), and of the row-ends method minus the full method "
              "(displaced). The reference's own error: the PSNR of its half-resolution version (8 x 8 rays for 16 x "
              "16) against it; differences between filters well below the gap between that and the filters' PSNR "
              "are resolved.", "",
              "| case | occluded px | reference: half vs full rays, PSNR dB | best filter | its PSNR | trilinear PSNR "
              "| ewa_vis - ewa, dB | rows - full, dB | displaced derivative ratio p50 / p99 / max | bounded |",
              "|---|---|---|---|---|---|---|---|---|---|"]
    per_case = defaultdict(list)
    for r in rows:
        per_case[r["case"]].append(r)
    for name, group in per_case.items():
        best = max(group, key=lambda r: r["psnr"] if math.isfinite(r["psnr"]) else -1e9)
        base = next((r for r in group if r["label"] == BASELINE.label), group[0])
        disp = next((r for r in group if r["label"] == _label("ewa", "displaced")), base)
        psnrs = {r["label"]: r["psnr"] for r in group}
        vis = " / ".join(_delta(psnrs, _label("ewa_vis", s), _label("ewa", s)) for s in ("displaced", "analytic"))
        rows_vs_full = _delta(psnrs, _label("ewa_vis_rows", "displaced"), _label("ewa_vis", "displaced"))
        lines.append(f"| {name} | {base['occluded_share']:.1%} | {base['reference_psnr_half']:.1f} | {best['label']} | "
                     f"{best['psnr']:.2f} | {base['psnr']:.2f} | {vis} | {rows_vs_full} | {disp['ratio_p50']:.2f} / "
                     f"{disp['ratio_p99']:.1f} / {disp['ratio_max']:.3g} | {disp['bounded_share']:.1%} |")
    lines += ["", "Reliefs: " + "; ".join(f"`{k}` {v}" for k, v in RELIEFS.items()) + ".",
              "Albedos: " + "; ".join(f"`{k}` {v}" for k, v in ALBEDOS.items()) + ".", ""]
    return "\n".join(lines)
