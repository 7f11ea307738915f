"""The refined-distance study's generated blocks in docs/maps.md and docs/techniques.md, made from the committed run
(``benchmarks/refined_distance/``: results.csv's fetch counts of the numpy twin, formats.csv's bake times);
``wgpuviewer docs`` writes them (``wgpuviewer.lab.docs``).

- ``refined distance baseline`` (maps.md): the centre-sampled baseline's extra fetches over ``distance`` at 45-80°;
- ``refined distance bake times`` (maps.md): the plain and refined bakes' times per size and path;
- ``refined distance savings`` (techniques.md): the refined map's fetch savings against ``distance`` and the
  baseline, over the run's maps;
- ``refined distance worked example`` (maps.md): the paper's point C rebuilt (the same run's example.csv,
  worked_example.png);
- ``refined distance bounded`` (maps.md): per map class, what the exact-visibility bound saves and what the
  conservative cut gets of it (the same run's bounded.csv, bounded_maps.csv);
- ``refined distance cost`` (maps.md): every map's fetches per height map and angle with the changes, the GPU
  renderer's agreement with the twin, the capped pixels;
- ``refined distance result``, ``... ablation`` (maps.md): what the condition and the bins change, and each bin
  layout against ``distance``;
- ``refined distance pits`` (maps.md): the condition on deeper and wider holes (pits.csv);
- ``refined distance storage`` (maps.md): float16 / float32 / 8-bit plain maps (results.csv, donnelly.csv);
- ``refined distance formats`` (maps.md): memory, build time and cost per map format (the report's table).
They compute from the committed CSVs and measure nothing."""

from __future__ import annotations

from collections import defaultdict
from pathlib import Path

from wgpuviewer.lab.harness.blocks import Block

from . import bounded, example, pits
from .report import formats_markdown
from .run import COSTS_TABLE, DONNELLY_TABLE, FORMATS_TABLE, TABLE
from .variants import CONDITION_PAIRS, OTHER_STORAGES, SINGLE_CONE

RUN = "benchmarks/refined_distance"
TWIN = "numpy twin"
DISTANCE, BASELINE, REFINED = "plain K=4", "plain before (maptools-2)", "4 sectors x 8 bands"
MIDDLE = (45.0, 60.0, 75.0, 80.0)  # "45-80°"
#: The reliefs of walls and bricks (their cells' walls are vertical), as techniques.md groups them.
WALL_LIKE = ("bricks", "wall", "plate", "grille")


def _fetches(root: Path) -> dict[tuple[str, float, str], float]:
    """(map, angle, variant) -> mean fetches per pixel of the numpy twin."""
    rows = TABLE.read(root / RUN / "results.csv")
    return {(r["heightmap"], float(r["angle"]), r["variant"]): float(r["fetches_mean"]) for r in rows
            if r["tracer"] == TWIN}


def _change(f, a: str, b: str, angles) -> dict[str, list[float]]:
    """map -> per angle, fetches(a) / fetches(b) - 1."""
    out = defaultdict(list)
    for (name, angle, variant), value in f.items():
        if variant == a and angle in angles and (name, angle, b) in f:
            out[name].append(value / f[(name, angle, b)] - 1.0)
    return dict(sorted(out.items()))


def _span(values) -> str:
    return f"{min(values):+.0%} to {max(values):+.0%}" if min(values) < max(values) else f"{min(values):+.0%}"


def baseline_body(root: Path) -> str:
    change = _change(_fetches(root), BASELINE, DISTANCE, MIDDLE)
    per_map = "; ".join(f"{name} {_span(v)}" for name, v in change.items())
    return (f"\nWith the centre-sampled map the tracer takes {_span([x for v in change.values() for x in v])} more "
            f"fetches than with this one at 45-80° (per map: {per_map}; the committed run, `{RUN}/`).\n")


def bake_body(root: Path) -> str:
    rows = FORMATS_TABLE.read(root / RUN / "formats.csv")
    by = {(r["format"], int(r["size"]), r["backend"]): r for r in rows}
    cells = []
    for kind in ("distance", "distance_refined"):
        for size in sorted({int(r["size"]) for r in rows if r["format"] == kind}):
            r = by.get((kind, size, "gpu"))
            if r is not None:
                cells.append(f"`{kind}` {size}² {float(r['build_s']):.1f} s"
                             + (" (extrapolated)" if r["extrapolated"] else ""))
    return f"\nBake times on the GPU path ({RUN}/formats.csv): {', '.join(cells)}.\n"


def savings_body(root: Path) -> str:
    f = _fetches(root)
    maps = sorted({name for name, _, _ in f})
    at = {a: _change(f, REFINED, DISTANCE, (a,)) for a in (45.0, 80.0)}
    wall = {k: v for k, v in _change(f, REFINED, BASELINE, MIDDLE).items() if k in WALL_LIKE}
    plain = _change(f, DISTANCE, BASELINE, MIDDLE)

    def span(d):
        return _span([x for v in d.values() for x in v])
    return (f"\nFetch savings at equal (exact) error, on the benchmark's views of its {len(maps)} maps ({', '.join(maps)}; "
            f"`{RUN}/`, every fetch to the hit): `distance_refined` against `distance`: {span(at[45.0])} at 45°, "
            f"{span(at[80.0])} at 80°; against a plain map sampled at the voxel centres (Donnelly 2005's "
            f"construction, the study's baseline) at 45-80° on the wall/brick-like reliefs ({', '.join(wall)}): "
            f"{span(wall)}; `distance` itself against that map at 45-80°: {span(plain)}.\n")


def example_body(root: Path) -> str:
    r = example.TABLE.read(root / RUN / "example.csv")[0]
    e = [float(x) for x in r["steps_euclidean"].split()]
    f = [float(x) for x in r["steps_refined"].split()]
    return (f"\nMeasured (`{RUN}/example.csv`): Euclidean value {float(r['euclidean']):.3f} texels, refined value "
            f"{float(r['refined']):.3f} (the directions sampled every {example.POLAR_STEP:g}° of polar angle and "
            f"{example.AZIMUTH_STEP:g}° of azimuth: a sampled least free path lies above the exact one), V1's hit "
            f"{float(r['hit_v1']):.3f} texels on at {float(r['horizon']):.1f}°. Donnelly's loop along V1 steps "
            f"{', '.join(f'{x:.3f}' for x in e)} with the Euclidean values and {', '.join(f'{x:.3f}' for x in f)} "
            f"with the refined ones. The product's conservative cut lets rays up to {float(r['cut_single']):.1f}° "
            f"(single cone) and {float(r['cut_sectors']):.1f}° ({example.CUT_SECTORS[-1]} sectors, the one towards "
            f"A) reach C's voxel.\n\n![the worked example](../{RUN}/{example.PLOT})\n")


def bounded_body(root: Path) -> str:
    rows = bounded.TABLE.read(root / RUN / "bounded.csv")
    for r in rows:
        r["angle"], r["fetches_mean"], r["passed"] = float(r["angle"]), float(r["fetches_mean"]), float(r["passed"])
    maps = bounded.MAPS_TABLE.read(root / RUN / "bounded_maps.csv")
    classes = bounded.by_class(rows)
    members = {c: sorted({r["heightmap"] for r in rows if r["class"] == c}) for c in classes}
    angles = sorted({r["angle"] for r in rows})

    def mean(c, v):
        return f"{100 * sum(classes[c][v]) / len(classes[c][v]):+.1f} %"

    lines = ["", f"The run's {rows[0]['size']} maps, views at {', '.join(f'{a:g}' for a in angles)}° (`{RUN}/bounded.csv`; "
             "mean change of fetches against `distance`; *share*: the part of the exact bound's saving the "
             "conservative cut gets):", "",
             "| class (maps) | paper's map, conservative cut | single cone, exact visibility | share | 4 x 8 bins, "
             "cut | 4 x 8 bins, exact visibility | share |", "|---|---|---|---|---|---|---|"]
    for c in classes:
        lines.append(f"| {c} ({', '.join(members[c])}) | {mean(c, bounded.PAPER)} | {mean(c, bounded.EXACT_SINGLE)} | "
                     f"{bounded.share(classes[c][bounded.PAPER], classes[c][bounded.EXACT_SINGLE]) + 0.0:.0%} | "
                     f"{mean(c, bounded.BINNED_CUT)} | {mean(c, bounded.EXACT_BINNED)} | "
                     f"{bounded.share(classes[c][bounded.BINNED_CUT], classes[c][bounded.EXACT_BINNED]) + 0.0:.0%} |")
    lines += [""]
    for c in classes:
        most = {v: -100 * min(classes[c][v]) for v in (bounded.EXACT_SINGLE, bounded.EXACT_BINNED)}
        lines.append(
            f"- {c}: with exact visibility the paper's single cone saves at most {most[bounded.EXACT_SINGLE]:.1f} % of "
            f"`distance`'s fetches on one view ({mean(c, bounded.EXACT_SINGLE)} on average), the 4 x 8 bins at most "
            f"{most[bounded.EXACT_BINNED]:.1f} %; the conservative cut gets "
            f"{bounded.share(classes[c][bounded.PAPER], classes[c][bounded.EXACT_SINGLE]) + 0.0:.0%} and "
            f"{bounded.share(classes[c][bounded.BINNED_CUT], classes[c][bounded.EXACT_BINNED]) + 0.0:.0%} of the "
            "average saving.")
    exceeded = [100 * float(m["check_exceeded"]) for m in maps]
    first = int(maps[0]["rays_per_texel"]) // int(maps[0]["batches"])
    drop = [100 * (1 - float(m["gain"]) / float(m["gain_first"])) for m in maps if float(m["gain_first"]) > 0]
    passed = [100 * r["passed"] for r in rows if "exact visibility" in r["variant"]]
    lines += ["", f"Sampling: {maps[0]['rays_per_texel']} random visible rays per texel and bin; fresh rays find a "
              f"stored value above their own free path on {min(exceeded):.2f}-{max(exceeded):.2f} % of them (99th "
              f"percentile of the excess at most {max(float(m['check_p99']) for m in maps):.3f} texel, largest "
              f"{max(float(m['check_max']) for m in maps):.1f}); with the exact maps the tracer's hit is not the exact "
              f"hit on at most {max(passed):.2f} % of the pixels. Between the first {first} rays per texel and bin and all "
              f"{maps[0]['rays_per_texel']}, the mean value gain over the plain map fell by {min(drop):.0f}-{max(drop):.0f} % "
              "(per map and map variant): the bound still lies above the exact value, so the savings above are upper "
              "bounds of the idea's; the conservative cut's own gain is in the report.", ""]
    return "\n".join(lines)


# --- docs/maps.md "Measured cost": the run's tables and what they say ---------------------------------------------

def _twins(root: Path) -> dict[tuple[str, float, str], dict]:
    """(map, angle, variant) -> the numpy twin's row."""
    return {(r["heightmap"], r["angle"], r["variant"]): r for r in TABLE.read(root / RUN / "results.csv")
            if r["tracer"] == TWIN}


def _ratio(by: dict, name: str, angle: float, a: str, b: str, key: str = "fetches_mean") -> float | None:
    x, y = by.get((name, angle, a)), by.get((name, angle, b))
    return x[key] / y[key] - 1.0 if x and y and y[key] else None


def _pct(x: float | None) -> str:
    return "-" if x is None else f"{100 * x:+.0f} %"


def _pcts(values, digits: int = 0) -> str:
    """The range of the changes ``values`` (fractions) in percent."""
    lo, hi = 100 * min(values), 100 * max(values)
    return f"{lo:+.{digits}f} %" if f"{lo:.{digits}f}" == f"{hi:.{digits}f}" else f"{lo:+.{digits}f} to {hi:+.{digits}f} %"


def _share(x: float) -> str:
    return "<0.1 %" if x < 0.0005 else f"{100 * x:.1f} %"


def _maps_angles(by: dict) -> tuple[list[str], list[float]]:
    return (list(dict.fromkeys(k[0] for k in by)), sorted({k[1] for k in by}))


#: The cost table's columns: (label, variant) and its changes (label, variant, against).
COST_COLUMNS = (("baseline", BASELINE), ("`distance`", DISTANCE), ("single cone", SINGLE_CONE),
                ("single cone, visibility on", CONDITION_PAIRS[0][0]), ("`distance_refined`", REFINED),
                ("`distance_refined`, visibility on", CONDITION_PAIRS[1][0]))
COST_CHANGES = (("`distance` vs baseline", DISTANCE, BASELINE), ("refined vs baseline", REFINED, BASELINE),
                ("refined vs `distance`", REFINED, DISTANCE))


def cost_body(root: Path) -> str:
    """Every product-relevant map's fetches (mean / SIMD-tile) per map and angle, the changes, the GPU renderer's
    agreement with the twin and the capped pixels."""
    by = _twins(root)
    maps, angles = _maps_angles(by)
    head = [c[0] for c in COST_COLUMNS] + [c[0] for c in COST_CHANGES]
    lines = ["", f"`{RUN}/results.csv`, the numpy twin (fetches mean / SIMD-tile; changes mean / SIMD-tile):", "",
             "| map | angle | " + " | ".join(head) + " |", "|---|---|" + "---|" * len(head)]
    for name in maps:
        for angle in angles:
            cells = []
            for _, variant in COST_COLUMNS:
                r = by.get((name, angle, variant))
                cells.append("-" if r is None else f"{r['fetches_mean']:.2f} / {r['fetches_simd']:.2f}")
            for _, a, b in COST_CHANGES:
                cells.append(f"{_pct(_ratio(by, name, angle, a, b))} / "
                             f"{_pct(_ratio(by, name, angle, a, b, 'fetches_simd'))}")
            lines.append(f"| {name} | {angle:g}° | " + " | ".join(cells) + " |")
    rows = TABLE.read(root / RUN / "results.csv")
    gpu = [(r, by.get((r["heightmap"], r["angle"], r["variant"]))) for r in rows if r["tracer"] != TWIN]
    gpu = [(g, t) for g, t in gpu if t and t["fetches_mean"]]
    lines.append("")
    for label, test in (("at 0-60°", lambda a: a <= 60), ("from 75° on", lambda a: a >= 75)):
        diff = [abs(g["fetches_mean"] / t["fetches_mean"] - 1.0) for g, t in gpu if test(g["angle"])]
        if diff:
            lines.append(f"The GPU renderer's mean fetches {label} differ from the twin's by at most "
                         f"{100 * max(diff):.3g} % ({len(diff)} rows).")
    capped = [r for r in by.values() if r["capped"]]
    lines.append("The twin capped no pixel." if not capped else "Pixels the twin capped: " + "; ".join(
        f"{r['variant']} on {r['heightmap']} at {r['angle']:g}° {_share(r['capped'])}" for r in capped) + ".")
    return "\n".join(lines) + "\n"


def result_body(root: Path) -> str:
    """What the condition and the bins change, over the run's maps and angles."""
    by = _twins(root)
    maps, angles = _maps_angles(by)

    def over(a, b, at=None):
        return [x for m in maps for g in (at or angles) if (x := _ratio(by, m, g, a, b)) is not None]

    (single_on, single), (binned_on, binned) = CONDITION_PAIRS
    return "\n".join([
        "",
        f"- The paper's condition on the single cone changes its mean fetches by {_pcts(over(single_on, single), 2)} "
        f"over the run's maps and angles ({', '.join(maps)}; {', '.join(f'{a:g}' for a in angles)}°); the single "
        f"cone without it is within {_pcts(over(single, DISTANCE), 2)} of `distance`; on the binned map the condition "
        f"changes {_pcts(over(binned_on, binned), 2)}.",
        "- `distance_refined` against `distance`: " + ", ".join(
            f"{_pcts(over(REFINED, DISTANCE, (a,)))} at {a:g}°" for a in (45.0, 60.0, 80.0)) +
        "; against the baseline: " + ", ".join(
            f"{_pcts(over(REFINED, BASELINE, (a,)))} at {a:g}°" for a in (45.0, 60.0, 80.0)) +
        f"; `distance` against the baseline: {_pcts(over(DISTANCE, BASELINE, (45.0,)))} at 45°, "
        f"{_pcts(over(DISTANCE, BASELINE, (75.0, 80.0)))} at 75-80°.",
        ""])


def pits_body(root: Path) -> str:
    """The condition on deeper and wider holes (``pits.csv``): its largest saving per bin layout, and Donnelly's
    error with and without it."""
    rows = pits.TABLE.read(root / RUN / "pits.csv")
    by = {(r["plate"], r["angle"], r["bins"], r["visibility"]): r for r in rows}
    lines = ["", f"`{RUN}/pits.csv`: plates {rows[0]['size']}², {rows[0]['rays']} random rays per plate and angle; "
             "fetches with the condition on against off:", ""]
    for bins in dict.fromkeys(r["bins"] for r in rows):
        pairs = [(by[k[:3] + ("off",)], r) for k, r in by.items() if k[2] == bins and k[3] == "on"
                 and k[:3] + ("off",) in by]
        change = [(on["fetches_mean"] / off["fetches_mean"] - 1.0, off, on) for off, on in pairs if off["fetches_mean"]]
        best, off, on = min(change, key=lambda c: c[0])
        steep = [c for c, o, _ in change if o["angle"] >= 45.0]
        donnelly = max(abs(on["error_p95_holes"] - off["error_p95_holes"]) for off, on in pairs)
        lines.append(f"- {bins} bins: at most {100 * best:+.1f} % of all rays' fetches "
                     f"({100 * (on['fetches_holes'] / off['fetches_holes'] - 1.0):+.1f} % of the rays that enter a "
                     f"hole), on {off['plate']} (holes {off['hole_depth']:g} texels deep) at {off['angle']:g}°"
                     + (f"; at 45° and beyond at most {100 * min(steep):+.1f} %" if steep else "") +
                     f"; Donnelly's loop at {rows[0]['budget']} iterations: the p95 error of the rays entering a hole "
                     f"moves by at most {donnelly:.2f} texel with the condition.")
    return "\n".join(lines + [""])


#: The ablation: the plain map on one sub-cell and the refined maps' bin layouts, against `distance`.
ABLATION = ("plain K=1", "8 sectors x 1 bands", "1 sectors x 8 bands", "2 sectors x 8 bands", REFINED)
BUILTINS = ("bricks", "bumps", "ridges", "wall")


def ablation_body(root: Path) -> str:
    """Change of mean fetches against `distance` per layout, at 45/60/80°, and how 4 x 8 compares with 8 x 1 and
    2 x 8."""
    by = _twins(root)
    maps, _ = _maps_angles(by)
    lines = ["", "| map | angle | " + " | ".join(ABLATION) + " |", "|---|---|" + "---|" * len(ABLATION)]
    for name in maps:
        for angle in (45.0, 60.0, 80.0):
            lines.append(f"| {name} | {angle:g}° | " + " | ".join(
                _pct(_ratio(by, name, angle, v, DISTANCE)) for v in ABLATION) + " |")

    def points(a, b, names):
        return [100 * (_ratio(by, m, g, b, DISTANCE) - _ratio(by, m, g, a, DISTANCE)) for m in names
                for g in (45.0, 60.0, 75.0, 80.0) if None not in (_ratio(by, m, g, a, DISTANCE),
                                                                    _ratio(by, m, g, b, DISTANCE))]
    sectors = points(REFINED, "8 sectors x 1 bands", [m for m in maps if m in BUILTINS])
    halves = points(REFINED, "2 sectors x 8 bands", maps)
    k1 = [x for m in maps for g in (45.0, 60.0, 75.0, 80.0)
          if (x := _ratio(by, m, g, "plain K=1", DISTANCE)) is not None]
    wins = sorted({m for m in maps for g in (45.0, 60.0, 80.0)
                   if (_ratio(by, m, g, "8 sectors x 1 bands", DISTANCE) or 0) < (_ratio(by, m, g, REFINED, DISTANCE) or 0)})
    lines += ["", f"At 45-80°: one sub-cell (K = 1) costs {_pcts(k1)} against `distance`; 4 x 8 bins take "
              f"{min(sectors):.0f} to {max(sectors):.0f} points fewer than 8 x 1 on the builtins "
              f"({', '.join(m for m in maps if m in BUILTINS)}) and {min(halves):.0f} to {max(halves):.0f} points "
              "fewer than 2 x 8 on every map"
              + (f"; 8 x 1 beats 4 x 8 on {', '.join(wins)} at some of 45/60/80°." if wins else "."), ""]
    return "\n".join(lines)


def storage_body(root: Path) -> str:
    """The plain map's storage: float16 as uploaded against float32, Donnelly's 8 bits against float16 (fetches and
    Donnelly's p95 error at 16 iterations and 60°)."""
    by = _twins(root)
    maps, angles = _maps_angles(by)
    f32, bits8 = OTHER_STORAGES

    def over(a, b, key="fetches_mean"):
        return [x for m in maps for g in angles if (x := _ratio(by, m, g, a, b, key)) is not None]
    donnelly = {(r["heightmap"], r["variant"]): r for r in DONNELLY_TABLE.read(root / RUN / "donnelly.csv")
                if r["regime"] == "fixed" and r["iterations"] == 16 and r["angle"] == 60.0}
    rise = [(donnelly[(m, bits8)]["error_p95"] - donnelly[(m, DISTANCE)]["error_p95"], m) for m in maps
            if (m, bits8) in donnelly and (m, DISTANCE) in donnelly]
    worst = max(rise, default=None)
    simd = max(over(bits8, DISTANCE, "fetches_simd"))
    return ("\nThe plain map as the renderer uploads it (float16, rounded down) takes "
            f"{_pcts(over(DISTANCE, f32), 2)} of float32's fetches; Donnelly's 8 bits take "
            f"{_pcts(over(bits8, DISTANCE), 1)} of float16's (SIMD-tile at most {100 * simd:+.1f} %)"
            + ("" if worst is None else
               f" and raise Donnelly's p95 error at 16 iterations and 60° by up to {worst[0]:.2f} texel ({worst[1]}: "
               f"{donnelly[(worst[1], DISTANCE)]['error_p95']:.2f} → {donnelly[(worst[1], bits8)]['error_p95']:.2f})")
            + f" (`{RUN}/`).\n")


def formats_body(root: Path) -> str:
    """The report's map-format table (``report.formats_markdown``)."""
    built = FORMATS_TABLE.read(root / RUN / "formats.csv")
    costs = COSTS_TABLE.read(root / RUN / "format_costs.csv")
    return "\n".join(["", f"`{RUN}/formats.csv` and `format_costs.csv`:", "", *formats_markdown(built, costs), ""])


BLOCKS = (Block("docs/maps.md", "refined distance baseline", f"{RUN}/results.csv", baseline_body, results=RUN),
          Block("docs/maps.md", "refined distance bake times", f"{RUN}/formats.csv", bake_body, results=RUN),
          Block("docs/techniques.md", "refined distance savings", f"{RUN}/results.csv", savings_body, results=RUN),
          Block("docs/maps.md", "refined distance worked example", f"{RUN}/example.csv", example_body, results=RUN),
          Block("docs/maps.md", "refined distance bounded", f"{RUN}/bounded.csv and {RUN}/bounded_maps.csv",
                bounded_body, results=RUN),
          Block("docs/maps.md", "refined distance cost", f"{RUN}/results.csv", cost_body, results=RUN),
          Block("docs/maps.md", "refined distance result", f"{RUN}/results.csv", result_body, results=RUN),
          Block("docs/maps.md", "refined distance pits", f"{RUN}/pits.csv", pits_body, results=RUN),
          Block("docs/maps.md", "refined distance ablation", f"{RUN}/results.csv", ablation_body, results=RUN),
          Block("docs/maps.md", "refined distance storage", f"{RUN}/results.csv and {RUN}/donnelly.csv",
                storage_body, results=RUN),
          Block("docs/maps.md", "refined distance formats", f"{RUN}/formats.csv and {RUN}/format_costs.csv",
                formats_body, results=RUN))
