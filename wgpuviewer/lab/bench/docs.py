"""docs/benchmarks.md's and docs/techniques.md's generated blocks made from committed bench runs: each run's
headline (bench's own ``report.headline_section``: the cheapest configuration per p95 budget, the winners against
``distance`` 256, the cheapest per angle) under one line naming the run, and per technique the mean and SIMD-tile
fetches of a run (``fetch_table``). For docs/techniques.md also: the time of a SIMD-tile fetch per technique
(``fetch_cost_body``), configurations per angle (``angle_table``), the exact walks at grazing views
(``grazing_table``), ``auto`` beyond the headline's angles and at 0° (``auto_beyond_body``, ``switch_cost_body``),
and auto's candidates, bins, budgets and weights from its code (``auto_table_body``: no run). They compute from the
results; they measure nothing. ``wgpuviewer docs`` (``wgpuviewer.lab.docs``) collects ``BLOCKS``.

In the bench room: it may import the product, the harness and bench.
"""

from __future__ import annotations

import math
from pathlib import Path

from wgpuviewer.lab.harness import stamp
from wgpuviewer.lab.harness.blocks import Block

from .report import HEADLINE_MAX_ANGLE, REFERENCE_CONFIG, config_label, headline_section, per_fetch_time
from .run import SUITES, TABLE

REDUCED = "benchmarks/llvmpipe-reduced/bench"
SMOKE = "benchmarks/llvmpipe-smoke/bench"
H100 = "benchmarks/h100"
H100_CONE = "benchmarks/h100_cone"
#: quadmax_pom beside what it combines: POM at its longest common counts and quadmax's exact walk.
HYBRID_CONFIGS = (("pom", "layers=32"), ("pom", "layers=64"), ("quadmax", "top_offset=-2 max_steps=1024"),
                  ("quadmax_pom", "skip_steps=8 layers=16"))


def _software(adapter: str) -> bool:
    return "(CPU)" in adapter or "llvmpipe" in adapter


def run_line(root: Path, folder: str, rows: list[dict]) -> str:
    """The run in one line: its command, adapter, date, frame, maps, angles, configurations and rows."""
    record = stamp.read(root / folder) or {}
    maps = list(dict.fromkeys(r["heightmap"] for r in rows))
    angles = sorted({r["angle"] for r in rows})
    configs = len({(r["technique"], r["params"]) for r in rows})
    adapter = record.get("adapter") or rows[0]["adapter"]
    return (f"`{folder}/` ([report](../{folder}/report.md)): `{record.get('command', 'command not recorded')}` on "
            f"**{adapter}**, code of {record.get('date', 'an unknown date')[:10]}; {rows[0]['resolution']}, "
            f"{len(maps)} height maps × {len(angles)} angles ({', '.join(f'{a:g}°' for a in angles)}), {configs} "
            f"configurations, {len(rows)} rows.")


def missing(root: Path, folder: str) -> str | None:
    """What a block says while its run has no results (it is being measured, or was removed)."""
    if (root / folder / "results.csv").is_file():
        return None
    return f"`{folder}/` holds no results: measure it (docs/benchmarks.md), then run `wgpuviewer docs`."


def headline_body(root: Path, folder: str) -> str:
    """A run's line and bench's headline section (its title left out: the page has its own)."""
    if missing(root, folder):
        return missing(root, folder)
    rows = TABLE.read(root / folder / "results.csv")
    suite = SUITES.get(rows[0]["suite"], SUITES["full"])
    section = headline_section(rows, {"suite": suite, "software": _software(rows[0]["adapter"])})
    lines = [run_line(root, folder, rows), "", *section[2:]]
    return "\n".join(line for i, line in enumerate(lines) if line or (i and lines[i - 1])).rstrip()


def fetch_table(root: Path, folder: str, techniques: tuple[str, ...]) -> str:
    """Per configuration of ``techniques``: mean and SIMD-tile fetches and worst p95 over the run's views up to the
    headline's angle, and the same at every angle."""
    if missing(root, folder):
        return missing(root, folder)
    rows = [r for r in TABLE.read(root / folder / "results.csv") if r["technique"] in techniques]
    lines = [f"`{folder}/`, every height map of the run:", "",
             f"| configuration | fetches (mean, ≤ {HEADLINE_MAX_ANGLE:g}°) | SIMD-tile fetches (≤ {HEADLINE_MAX_ANGLE:g}°) | "
             f"worst p95 (≤ {HEADLINE_MAX_ANGLE:g}°, texels) | SIMD-tile fetches (all angles) |", "|---|---|---|---|---|"]
    for key in dict.fromkeys((r["technique"], r["params"]) for r in rows):
        mine = [r for r in rows if (r["technique"], r["params"]) == key]
        low = [r for r in mine if r["angle"] <= HEADLINE_MAX_ANGLE]

        def mean(vs, column):
            values = [v[column] for v in vs if v.get(column) is not None and math.isfinite(v[column])]
            return f"{sum(values) / len(values):.1f}" if values else "–"

        worst = max((r["uv_err_p95"] for r in low), default=float("nan"))
        lines.append(f"| {config_label(key)} | {mean(low, 'fetches_mean')} | {mean(low, 'fetches_simd')} | "
                     f"{worst:.2f} | {mean(mine, 'fetches_simd')} |")
    return "\n".join(lines)


# --- docs/techniques.md: what the runs say about single techniques ------------------------------------------------

def _rows(root: Path, folder: str) -> list[dict]:
    return TABLE.read(root / folder / "results.csv")


def _p95(x: float) -> str:
    return f"{x:.2f}" if x < 10 else f"{x:.1f}"


def _mean(values) -> float:
    values = [v for v in values if v is not None and math.isfinite(v)]
    return sum(values) / len(values) if values else float("nan")


def angle_table(root: Path, folder: str, configs: tuple[tuple[str, str], ...], angles: tuple[float, ...]) -> str:
    """Per configuration and angle: SIMD-tile fetches (mean over the run's maps) / worst p95 UV error over them."""
    if missing(root, folder):
        return missing(root, folder)
    rows = _rows(root, folder)
    lines = [f"`{folder}/`, every height map of the run; per angle the SIMD-tile fetches (mean over the maps) / the "
             "worst p95 UV error (texels, over the maps):", "",
             "| configuration | " + " | ".join(f"{a:g}°" for a in angles) + " |", "|---|" + "---|" * len(angles)]
    for key in configs:
        cells = []
        for angle in angles:
            mine = [r for r in rows if (r["technique"], r["params"]) == key and r["angle"] == angle]
            cells.append(f"{_mean(r['fetches_simd'] for r in mine):.1f} / {_p95(max(r['uv_err_p95'] for r in mine))}"
                         if mine else "–")
        lines.append(f"| {config_label(key)} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def grazing_table(root: Path, folder: str, techniques: tuple[str, ...], angles: tuple[float, ...]) -> str:
    """Per height map of the run: each technique's mean fetches per pixel at ``angles`` (its default settings),
    with the capped share where a ray was capped."""
    if missing(root, folder):
        return missing(root, folder)
    rows = [r for r in _rows(root, folder) if r["technique"] in techniques and r["angle"] in angles]
    by = {(r["heightmap"], r["technique"], r["angle"]): r for r in rows}
    maps = list(dict.fromkeys(r["heightmap"] for r in rows))
    at = " / ".join(f"{a:g}°" for a in angles)
    lines = [f"`{folder}/`: mean fetches per pixel at {at} (the frame's centre angle; capped share where a ray was "
             "capped):", "", "| height map | " + " | ".join(f"`{t}`" for t in techniques) + " |",
             "|---|" + "---|" * len(techniques)]

    def cell(r):
        if r is None:
            return "–"
        capped = r["capped_fraction"] or 0.0
        return f"{r['fetches_mean']:.1f}" + (f" ({capped:.1%} capped)" if capped > 0 else "")

    for name in maps:
        lines.append(f"| {name} | " + " | ".join(" / ".join(cell(by.get((name, t, a))) for a in angles)
                                                for t in techniques) + " |")
    capped = [r for r in rows if (r["capped_fraction"] or 0.0) > 0]
    lines += ["", "No ray of these rows was capped." if not capped else
              f"Capped rays in {len(capped)} of {len(rows)} rows, at most {max(r['capped_fraction'] for r in capped):.1%}."]
    return "\n".join(lines)


def fetch_cost_body(root: Path, folder: str) -> str:
    """bench's time per SIMD-tile fetch per technique (``report.per_fetch_time``) in POM fetches, beside the weights
    auto's table uses (``autotable.COST_WEIGHTS``, code); and quadmax against distance per angle."""
    from wgpuviewer.techniques.auto.autotable import COST_WEIGHTS

    if missing(root, folder):
        return missing(root, folder)
    rows = _rows(root, folder)
    per = per_fetch_time(rows)
    pom = per.get("pom")
    lines = [f"`{folder}/` on **{rows[0]['adapter']}**: the time of one SIMD-tile fetch (median over the run's rows "
             "with fetches of (time / basic − 1) / SIMD-tile fetches), in POM fetches, beside the weight auto's table "
             "gives the technique (`autotable.COST_WEIGHTS`):", "",
             "| technique | × basic per SIMD-tile fetch | in POM fetches | `COST_WEIGHTS` |", "|---|---|---|---|"]
    for technique, value in per.items():
        weight = COST_WEIGHTS.get(technique)
        relative = f"{value / pom:.2f}" if pom else "–"
        lines.append(f"| {technique} | {value:.3f} | {relative} | {'–' if weight is None else f'{weight:g}'} |")
    angles = sorted({r["angle"] for r in rows if 0 < r["angle"] <= HEADLINE_MAX_ANGLE})
    versus = []
    for angle in angles:
        q = {r["heightmap"]: r for r in rows if r["technique"] == "quadmax" and r["angle"] == angle}
        d = {r["heightmap"]: r for r in rows if (r["technique"], r["params"]) == REFERENCE_CONFIG
             and r["angle"] == angle}
        both = [m for m in q if m in d and q[m]["fetches_simd"] > 0]
        if both:
            fetches = _geometric_mean([d[m]["fetches_simd"] / q[m]["fetches_simd"] for m in both])
            time = _geometric_mean([d[m]["ratio_to_basic"] / q[m]["ratio_to_basic"] for m in both])
            versus.append(f"{angle:g}°: {fetches:.1f}× the SIMD-tile fetches, {time:.2f}× the time")
    if versus:
        lines += ["", f"`{config_label(REFERENCE_CONFIG)}` against `quadmax` (geometric mean over the maps): "
                  + "; ".join(versus) + "."]
    return "\n".join(lines)


def _geometric_mean(xs) -> float:
    xs = [x for x in xs if x > 0 and math.isfinite(x)]
    return math.exp(sum(math.log(x) for x in xs) / len(xs)) if xs else float("nan")


def _budget(params: str) -> float:
    return float(dict(p.split("=") for p in params.split())["max_error"])


def auto_beyond_body(root: Path, folder: str) -> str:
    """auto's worst p95 per budget at the run's angles beyond the headline's (where its table is held to its own
    rays only), with the map it was on; bold where it exceeds the budget."""
    if missing(root, folder):
        return missing(root, folder)
    rows = [r for r in _rows(root, folder) if r["technique"] == "auto" and r["angle"] > HEADLINE_MAX_ANGLE]
    angles = sorted({r["angle"] for r in rows})
    if not angles:
        return f"`{folder}/` holds no `auto` rows beyond {HEADLINE_MAX_ANGLE:g}°."
    lines = [f"`{folder}/`: `auto`'s worst p95 UV error over the run's maps beyond {HEADLINE_MAX_ANGLE:g}° (texels; "
             "the map; **bold**: above the budget):", "",
             "| configuration | " + " | ".join(f"{a:g}°" for a in angles) + " |", "|---|" + "---|" * len(angles)]
    for params in dict.fromkeys(r["params"] for r in rows):
        cells = []
        for angle in angles:
            worst = max((r for r in rows if r["params"] == params and r["angle"] == angle),
                        key=lambda r: r["uv_err_p95"])
            text = f"{_p95(worst['uv_err_p95'])} ({worst['heightmap']})"
            cells.append(f"**{text}**" if worst["uv_err_p95"] > _budget(params) else text)
        lines.append(f"| {config_label(('auto', params))} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def switch_cost_body(root: Path, folder: str) -> str:
    """At 0° (head-on: auto's table picks no search there): auto's time against basic beside normal's and POM 4's,
    per height map of the run."""
    if missing(root, folder):
        return missing(root, folder)
    rows = [r for r in _rows(root, folder) if r["angle"] == 0.0]
    maps = list(dict.fromkeys(r["heightmap"] for r in rows))
    autos = list(dict.fromkeys(r["params"] for r in rows if r["technique"] == "auto"))
    configs = [("normal", "-"), ("pom", "layers=4"), *(("auto", p) for p in autos)]
    by = {(r["heightmap"], r["technique"], r["params"]): r for r in rows}
    lines = [f"`{folder}/` on **{rows[0]['adapter'] if rows else 'no adapter'}** at 0°: time / basic "
             "(SIMD-tile fetches):", "",
             "| height map | " + " | ".join(config_label(c) for c in configs) + " |", "|---|" + "---|" * len(configs)]
    for name in maps:
        cells = []
        for key in configs:
            r = by.get((name, *key))
            cells.append("–" if r is None else f"{r['ratio_to_basic']:.2f}× ({r['fetches_simd']:.1f})")
        lines.append(f"| {name} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def _candidate(name: str, params: dict) -> str:
    if name == "pom":
        return f"POM {params['layers']}"
    if name == "relief":
        return f"relief {params['linear_steps']}+{params['binary_steps']}"
    return name


def auto_table_body(root: Path) -> str:
    """auto's candidates, bins, budgets and cost weights, from its code (``autotable``)."""
    from wgpuviewer.techniques.auto import autotable as at

    edges = at.edge_angles()
    budgets = at.budgets()
    weights = ", ".join(f"{name} {w:g}" for name, w in at.COST_WEIGHTS.items())
    return (f"`autotable`: **{len(at.AUTO_CANDIDATES)} candidates**, cheapest first: "
            f"{', '.join(_candidate(n, p) for n, p in at.AUTO_CANDIDATES)} (relief n+b: n linear, b binary steps). "
            f"**{at.AUTO_BINS} bins** of the view angle, {at.AUTO_BINS_PER_OCTAVE} per octave of tan θ: bin 0 below "
            f"{edges[1]:.2f}°, the last from {edges[-2]:.1f}° on (open-ended, measured at {edges[-1]:g}°). "
            f"**{len(budgets)} budgets**: {', '.join(f'{b:g}' for b in budgets)} texels. **Cost weights** (the "
            f"time of one SIMD-tile fetch in POM fetches): {weights}.")


BLOCKS = (
    Block("docs/benchmarks.md", "llvmpipe reduced", f"{REDUCED}/results.csv",
          lambda root: headline_body(root, REDUCED), results=REDUCED),
    Block("docs/benchmarks.md", "llvmpipe smoke", f"{SMOKE}/results.csv",
          lambda root: headline_body(root, SMOKE), results=SMOKE),
    Block("docs/benchmarks.md", "h100", f"{H100}/results.csv", lambda root: headline_body(root, H100), results=H100),
    Block("docs/benchmarks.md", "h100 cone", f"{H100_CONE}/results.csv",
          lambda root: headline_body(root, H100_CONE), results=H100_CONE),
    Block("docs/techniques.md", "exact tracers' fetches", f"{REDUCED}/results.csv",
          lambda root: fetch_table(root, REDUCED, ("maxmip", "distance", "distance_refined", "quadmax", "cone", "auto")),
          results=REDUCED),
    Block("docs/techniques.md", "time per fetch", f"{REDUCED}/results.csv", lambda root: fetch_cost_body(root, REDUCED),
          results=REDUCED),
    Block("docs/techniques.md", "quadmax_pom against quadmax", f"{REDUCED}/results.csv",
          lambda root: angle_table(root, REDUCED, HYBRID_CONFIGS, (45.0, 60.0, 75.0, 80.0)), results=REDUCED),
    Block("docs/techniques.md", "auto's table", "auto's code (autotable)", auto_table_body),
    Block("docs/techniques.md", "auto beyond 80°", f"{REDUCED}/results.csv",
          lambda root: auto_beyond_body(root, REDUCED), results=REDUCED),
    Block("docs/techniques.md", "auto's switch", f"{SMOKE}/results.csv", lambda root: switch_cost_body(root, SMOKE),
          results=SMOKE),
    Block("docs/techniques.md", "grazing fetches", f"{REDUCED}/results.csv",
          lambda root: grazing_table(root, REDUCED, ("maxmip", "quadmax", "distance", "distance_refined", "cone"),
                                     (85.0, 89.0)), results=REDUCED),
)
