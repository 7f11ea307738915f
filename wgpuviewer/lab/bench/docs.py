"""docs/benchmarks.md's and docs/techniques.md's generated blocks made from committed bench runs: each run's
headline (bench's own ``report.headline_section``: the cheapest configuration per p95 budget, the winners against
``distance`` 256, the cheapest per angle) under one line naming the run, and per technique the mean and SIMD-tile
fetches of a run (``fetch_table``). ``wgpuviewer docs`` (``wgpuviewer.lab.docs``) collects ``BLOCKS``.

In the bench room: it may import the product, the harness and bench.
"""

from __future__ import annotations

import math
from pathlib import Path

from wgpuviewer.lab.harness import stamp
from wgpuviewer.lab.harness.blocks import Block

from .report import HEADLINE_MAX_ANGLE, config_label, headline_section
from .run import SUITES, TABLE

REDUCED = "benchmarks/llvmpipe-reduced/bench"
SMOKE = "benchmarks/llvmpipe-smoke/bench"
H100 = "benchmarks/h100"
H100_CONE = "benchmarks/h100_cone"


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
)
