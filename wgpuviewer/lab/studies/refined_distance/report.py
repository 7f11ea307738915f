"""The refined-distance study's report: ``report.md`` (each variant's fetches over the plain map's, the paper's
condition, grazing views, Donnelly's regime, the map formats) and its plot (``ratio_to_distance.png``)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

from maptools.kinds.distance_refined.slot import REFINED_MAX_ANGLE
from wgpuviewer.lab.harness.header import Header
from wgpuviewer.lab.harness.plots import MISSING, pyplot, save_png

from . import bounded, example, formats, pits
from .variants import CONDITION_PAIRS, OTHER_STORAGES, PLAIN, PRODUCT, VARIANTS

#: Files of a run (a stale one from an earlier layout is removed by the lead, not here).
PLOT = "ratio_to_distance.png"


@dataclass
class Results:
    rows: list[dict]
    donnelly: list[dict]
    formats: list[dict]
    costs: list[dict]
    pits: list[dict]
    bounded: list[dict] = field(default_factory=list)  # bounded.TABLE's rows
    bounded_maps: list[dict] = field(default_factory=list)  # bounded.MAPS_TABLE's
    example: example.Example | None = None  # the paper's worked example
    cuts: dict = field(default_factory=dict)  # sectors -> the conservative cut at C (degrees)
    example_plotted: bool = False


def _twins(rows: list[dict]) -> list[dict]:
    return [r for r in rows if r["tracer"] == "numpy twin"]


def ratios(rows: list[dict], key: str = "fetches_mean") -> dict[tuple[str, str, float], float]:
    """(height map, variant, angle) -> the variant's ``key`` over the plain K=4 map's (the `distance` technique's)
    on the same view, numpy-twin rows."""
    twins = _twins(rows)
    plain = {(r["heightmap"], r["angle"]): r[key] for r in twins if r["variant"] == PLAIN}
    return {(r["heightmap"], r["variant"], r["angle"]): r[key] / plain[r["heightmap"], r["angle"]]
            for r in twins if (r["heightmap"], r["angle"]) in plain and plain[r["heightmap"], r["angle"]] > 0}


def plot(rows: list[dict], path: Path) -> bool:
    """Fetches per pixel over the `distance` map's (plain K=4) against the view angle: one panel per height map,
    one line per variant; the visibility-on maps dashed in the colour of their visibility-off twin. False when
    matplotlib is missing (the tables still stand)."""
    with pyplot() as plt:
        if plt is None:
            return False
        _draw(plt, rows, path)
    return True


def _draw(plt, rows: list[dict], path: Path) -> None:
    by = ratios(rows)
    maps = list(dict.fromkeys(k[0] for k in by))
    cols = min(3, len(maps)) or 1
    panel_rows = math.ceil(len(maps) / cols) or 1
    fig, axes = plt.subplots(panel_rows, cols, figsize=(4.2 * cols, 3.2 * panel_rows), squeeze=False)
    off_of = {on: off for on, off in CONDITION_PAIRS}
    names = [v.name for v in VARIANTS if v.name != PLAIN]
    colours = {n: plt.cm.tab10(i % 10) for i, n in enumerate(n for n in names if n not in off_of)}
    sizes = {r["heightmap"]: r["size"] for r in rows}
    for ax, name in zip(axes.ravel(), maps):
        for variant in names:
            mine = sorted((a, r) for (m, v, a), r in by.items() if m == name and v == variant)
            if not mine:
                continue
            angles, ratio = zip(*mine)
            on = variant in off_of
            ax.plot(angles, ratio, "--" if on else "-", marker="x" if on else "o", ms=3,
                    lw=2.0 if PRODUCT in variant else 1.1, color=colours[off_of.get(variant, variant)],
                    label=variant)
        ax.axhline(1.0, color="k", lw=0.6)
        ax.set_title(f"{name} ({sizes[name]})", fontsize=9)
        ax.set_xlabel("view angle at the frame centre (deg)", fontsize=7)
        ax.set_ylabel("fetches / distance map's", fontsize=7)
        ax.tick_params(labelsize=7)
        ax.grid()
    for ax in axes.ravel()[len(maps):]:
        ax.axis("off")
    handles, labels = axes.ravel()[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=min(4, len(labels)) or 1, fontsize=7, frameon=False)
    fig.suptitle("Fetches to the exact hit over the `distance` map's (plain K=4), mean per pixel; "
                 "dashed: the paper's visibility condition on", fontsize=9)
    fig.tight_layout(rect=(0, 0.1, 1, 0.96))
    save_png(fig, path, tight=False)


#: The report's change columns: (label, variant, against which variant).
CHANGES = (("K=4 vs before", PLAIN, VARIANTS[0].name), ("product vs before", PRODUCT, VARIANTS[0].name),
           ("product vs K=4", PRODUCT, PLAIN),
           *((f"K=4 {name.split(', ')[1]} vs float16", name, PLAIN) for name in OTHER_STORAGES))


def _pct(a: float | None, b: float | None) -> str:
    return "-" if not (a and b) else f"{100 * (a / b - 1):+.0f} %"


def _change(by: dict, variant: str, base: str) -> str:
    a, b = by.get(variant), by.get(base)
    if not (a and b):
        return "-"
    return f"{_pct(a['fetches_mean'], b['fetches_mean'])} / {_pct(a['fetches_simd'], b['fetches_simd'])}"


def report(res: Results, header: Header, plotted: bool | None) -> str:
    """Markdown: the worked example and the bound, the paper's condition (on vs off), per height map every variant's
    fetches by angle with the changes, grazing views, Donnelly's regime, the map formats. ``plotted`` None: a run of
    the bound alone (no variants' picture)."""
    lines = [*header.lines(), ""]
    if plotted is not None:
        lines += ["Every fetch to the final hit (volume fetches and exact-cell gathers), the same tracer (the numpy twin "
                  "of `distance.wgsl`) for every map; the GPU renderer beside it where a technique binds the map. "
                  "Changes: mean / SIMD-tile. " + (f"Picture (ratios to the `distance` map): [{PLOT}]({PLOT})."
                                                  if plotted else MISSING), ""]
    if res.example is not None:
        lines += example.section(res.example, res.cuts, f"Picture: [{example.PLOT}]({example.PLOT})."
                                 if res.example_plotted else MISSING)
    lines += bounded.section(res.bounded, res.bounded_maps)
    if res.rows:
        lines += _condition_section(res.rows)
    lines += pits.section(res.pits)
    lines += _variant_sections(res.rows)
    lines += _grazing_section(res.rows)
    lines += _donnelly_section(res.donnelly)
    lines += _formats_section(res.formats, res.costs)
    return "\n".join(lines) + "\n"


def _condition_section(rows: list[dict]) -> list[str]:
    lines = ["## The paper's visibility condition", ""]
    twins = _twins(rows)
    lines += ["Fetches with the condition over the same map without it (mean / SIMD-tile), per view angle: "
              "single cone (sectors 1 x bands 1, the paper's map) and the binned map (the product's bins).", "",
              "| height map | angle | single cone: on vs off | binned: on vs off |", "|---|---|---|---|"]
    by = {(r["heightmap"], r["angle"], r["variant"]): r for r in twins}
    for name, angle in dict.fromkeys((r["heightmap"], r["angle"]) for r in twins):
        cells = [_change({v: by.get((name, angle, v)) for v in pair}, *pair) for pair in CONDITION_PAIRS]
        lines.append(f"| {name} | {angle:g}° | " + " | ".join(cells) + " |")
    return lines + [""]


def _variant_sections(rows: list[dict]) -> list[str]:
    lines = []
    present = dict.fromkeys(r["variant"] for r in _twins(rows))
    names = [v.name for v in VARIANTS if v.name in present]
    for name in dict.fromkeys(r["heightmap"] for r in rows):
        mine = [r for r in _twins(rows) if r["heightmap"] == name]
        if not mine:
            continue
        lines += [f"## {name} ({mine[0]['size']})", "",
                  "| angle | " + " | ".join(names + [c[0] for c in CHANGES]) + " |",
                  "|---|" + "---|" * (len(names) + len(CHANGES))]
        for angle in dict.fromkeys(r["angle"] for r in mine):
            cells, by = [], {r["variant"]: r for r in mine if r["angle"] == angle}
            for v in names:
                r = by.get(v)
                cells.append(f"{r['fetches_mean']:.2f} / {r['fetches_simd']:.2f}" if r else "-")
            cells += [_change(by, variant, base) for _, variant, base in CHANGES]
            lines.append(f"| {angle:g}° | " + " | ".join(cells) + " |")
        builds = {r["variant"]: r for r in mine}
        lines += ["", "build (s, cache included) and memory (MiB): " + "; ".join(
            f"{v}: {builds[v]['build_s']:.1f} s, {builds[v]['memory_mib']:.1f} MiB" for v in names if v in builds),
            ""]
        gpu = [r for r in rows if r["heightmap"] == name and r["tracer"] != "numpy twin"]
        if gpu:
            lines.append(f"GPU renderer ({gpu[0]['tracer']}), same views: " + "; ".join(
                f"{r['variant']} {r['angle']:g}° {r['fetches_mean']:.2f} / {r['fetches_simd']:.2f}" for r in gpu))
            lines.append("")
    return lines


#: Views at or beyond this angle are the grazing section's.
GRAZING = 85.0


def _grazing_section(rows: list[dict]) -> list[str]:
    graze = [r for r in rows if r["angle"] >= GRAZING and r["variant"] in (PLAIN, PRODUCT)]
    if not graze:
        return []
    lines = ["## Grazing views", "",
             f"Fetches (mean / SIMD-tile) and the pixels the tracer's cap stopped (capped), at {GRAZING:g}° and "
             f"beyond; rays past the refined map's {REFINED_MAX_ANGLE:g}° cone use its plain volume. The GPU rows "
             "are the product as it is; the twin models the sphere-step / cell-solve loop alone, so a GPU row below "
             "its twin is the product's own grazing finish at work.", "",
             "| height map | angle | map | tracer | fetches | capped |", "|---|---|---|---|---|---|"]
    for r in graze:
        lines.append(f"| {r['heightmap']} | {r['angle']:g}° | {r['variant']} | {r['tracer']} | "
                     f"{r['fetches_mean']:.2f} / {r['fetches_simd']:.2f} | {100 * r['capped']:.2f} % |")
    return lines + [""]


def _donnelly_section(rows: list[dict]) -> list[str]:
    if not rows:
        return []
    budgets = sorted({r["iterations"] for r in rows if r["regime"] == "fixed"})
    lines = ["## Donnelly's regime: fixed iterations, trilinear lookups, no finish", "",
             "A float64 numpy model of Donnelly's loop (`studies/refined_distance/donnelly.py`): from the surface "
             "plane, N steps of the trilinearly filtered stored distance, the point reached is the hit (no finish). "
             "Error: |uv reached - uv of the float64 exact first hit| in texels, p95 / max; passed: rays whose point "
             "lies past the exact hit (a trilinear blend of conservative voxels can step through the surface). "
             "Exact: the product's tracer (the twin; its fetches include the exact cell gathers).", "",
             "| height map | angle | map | " + " | ".join(f"N={n} p95 / max (passed)" for n in budgets) +
             " | exact: fetches (p95 / max) |", "|---|---|---|" + "---|" * (len(budgets) + 1)]
    keys = dict.fromkeys((r["heightmap"], r["angle"], r["variant"]) for r in rows)
    for key in keys:
        mine = {r["iterations"]: r for r in rows if (r["heightmap"], r["angle"], r["variant"]) == key}
        cells = [f"{mine[n]['error_p95']:.2f} / {mine[n]['error_max']:.2f} ({100 * mine[n]['passed']:.1f} %)"
                 if n in mine else "-" for n in budgets]
        exact = mine.get(None)
        cells.append(f"{exact['fetches_mean']:.1f} ({exact['error_p95']:.3f} / {exact['error_max']:.3f})"
                     if exact else "-")
        lines.append(f"| {key[0]} | {key[1]:g}° | {key[2]} | " + " | ".join(cells) + " |")
    return lines + [""]


def formats_markdown(built: list[dict], costs: list[dict]) -> list[str]:
    """ONE table: per map format, bytes per texel, build time (GPU path / CPU reference) per size, and the GPU
    renderer's fetches / SIMD-tile fetches / ms to the exact hit per angle (per height map of the costs)."""
    sizes = sorted({b["size"] for b in built})
    cost_keys = list(dict.fromkeys((c["heightmap"], c["angle"]) for c in costs))
    head = (["format", "bytes / texel"] + [f"build {n}² GPU / CPU (s)" for n in sizes] +
            [f"{m} {a:g}°: fetches / SIMD / ms" for m, a in cost_keys])
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for fmt in formats.FORMATS:
        mine = [b for b in built if b["format"] == fmt]
        if not mine:
            continue
        cells = [f"`{fmt}`", f"{mine[0]['bytes_per_texel']:.1f}"]
        for n in sizes:
            pair = []
            for backend in formats.BACKENDS:
                b = next((b for b in mine if b["size"] == n and b["backend"] == backend), None)
                pair.append("-" if b is None else f"{'~' if b['extrapolated'] else ''}{b['build_s']:.2f}")
            cells.append(" / ".join(pair))
        for m, a in cost_keys:
            c = next((c for c in costs if (c["heightmap"], c["angle"], c["format"]) == (m, a, fmt)), None)
            cells.append("-" if c is None else f"{c['fetches_mean']:.1f} / {c['fetches_simd']:.1f} / {c['ms']:.2f}")
        lines.append("| " + " | ".join(cells) + " |")
    return lines


def _formats_section(built: list[dict], costs: list[dict]) -> list[str]:
    if not built:
        return []
    settings = "; ".join(dict.fromkeys(f"`{b['format']}` {b['settings']}" for b in built if b["size"] ==
                                       max(x["size"] for x in built) and b["backend"] == "gpu"))
    return ["## Map formats: memory, build time, cost to the exact hit", "",
            "Bytes per height-map texel of the texture(s) the renderer uploads; build time uncached, GPU path / CPU "
            "reference (~: not run, extrapolated in proportion to the texels from the largest size measured within "
            "the suite's budget); fetches (mean / SIMD-tile 8x4) and median ms per frame of the format's technique "
            "in the GPU renderer (on a software adapter only the fetches and the ms ratios mean anything). "
            f"Settings at the largest size: {settings}.", "", *formats_markdown(built, costs), ""]
