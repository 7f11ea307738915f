"""The accuracy study's tables, made from its CSV rows (``run.RESULTS``, ``run.SHADOWS``) for report.md and
docs/accuracy.md's blocks: one table per height map (a row per setting, a column per angle, each cell **p95 / max
UV error · mean fetches** and the capped share where rays were capped), and the self-shadowing table (per technique
and light elevation, over the maps)."""

from __future__ import annotations

import math

import numpy as np


def label(params: dict) -> str:
    """A setting's parameter overrides as the tables and the CSV name them: ``k=v, k=v``, ``-`` for none."""
    return ", ".join(f"{k}={v}" for k, v in params.items()) or "-"


def texels(x: float) -> str:
    if not math.isfinite(x):
        return "–"  # every ray capped or declined by the reference
    return f"{x:.3f}" if x < 10 else f"{x:.1f}"


def cell(row: dict) -> str:
    """p95 / max UV error · mean fetches, and the capped share where rays were capped."""
    text = f"{texels(row['error_p95'])} / {texels(row['error_max'])} · {row['fetches_mean']:.1f}"
    if row["capped"] > 0:
        text += f" · {row['capped']:.1%} capped" if row["capped"] >= 0.001 else " · <0.1% capped"
    return text


def facts(rows: list[dict]) -> str:
    """What every cell was measured with: the relief depth, the map sizes, the rays."""
    scales = ", ".join(f"{s:g}" for s in dict.fromkeys(r["height_scale"] for r in rows))
    sizes = ", ".join(dict.fromkeys(f"{r['width']}x{r['height']}" for r in rows))
    rays = ", ".join(str(n) for n in dict.fromkeys(r["rays"] for r in rows))
    return (f"height_scale {scales}; {sizes} maps; {rays} random rays per map and angle (uniform entry points, "
            "random azimuth, seed 0), the same rays for every setting")


def map_tables(rows: list[dict]) -> list[str]:
    """Per height map, in the rows' order: a heading with its size and a table, a row per setting (technique and
    params) and a column per angle."""
    lines = []
    for name in dict.fromkeys(r["heightmap"] for r in rows):
        mine = [r for r in rows if r["heightmap"] == name]
        angles = list(dict.fromkeys(r["angle"] for r in mine))
        by = {(r["technique"], r["params"], r["angle"]): r for r in mine}
        lines += [f"## {name} ({mine[0]['width']}x{mine[0]['height']})", "",
                  "| technique | params | " + " | ".join(f"{a:g}°" for a in angles) + " |",
                  "|---|---|" + "---|" * len(angles)]
        for technique, params in dict.fromkeys((r["technique"], r["params"]) for r in mine):
            cells = " | ".join(cell(by[technique, params, a]) if (technique, params, a) in by else "–"
                               for a in angles)
            lines.append(f"| {technique} | {params} | {cells} |")
        lines.append("")
    return lines[:-1]


def shadow_sentence(rows: list[dict]) -> str:
    """How the self-shadowing rows were measured: rays, view angle, light azimuth, maps."""
    first = rows[0]
    maps = ", ".join(dict.fromkeys(r["heightmap"] for r in rows))
    return (f"{first['rays']} random rays per map at {first['view_angle']:g}° from the normal (random azimuths), "
            f"lights at azimuth {first['light_azimuth']:g}°, on {maps}.")


def shadow_table(rows: list[dict]) -> list[str]:
    """Per technique (a row) and light elevation (a column): the wrong hard states from the technique's own view hit
    in % (mean over the maps, the worst map in brackets), the mean soft difference, the mean fetches per hard
    shadow ray."""
    elevations = list(dict.fromkeys(r["elevation"] for r in rows))
    lines = ["| technique | " + " | ".join(f"light {e:g}°" for e in elevations) + " |",
             "|---|" + "---|" * len(elevations)]
    for technique in dict.fromkeys(r["technique"] for r in rows):
        cells = []
        for e in elevations:
            sel = [r for r in rows if r["technique"] == technique and r["elevation"] == e]
            wrong = [100 * r["hard_wrong_own_hit"] for r in sel]
            cells.append(f"{np.mean(wrong):.2f} % ({max(wrong):.2f}) / "
                         f"{np.mean([r['soft_diff_own_hit'] for r in sel]):.4f} · "
                         f"{np.mean([r['hard_fetches'] for r in sel]):.1f}")
        lines.append(f"| {technique} | " + " | ".join(cells) + " |")
    return lines


def report(rows: list[dict], shadows: list[dict]) -> list[str]:
    """report.md after its header: what was measured, the tables per map, the self-shadowing table."""
    return [
        f"- measured: {facts(rows)}", "",
        "Each cell: **p95 / max UV error** in texels (wrap-aware) between the probe's hit and the float64 first hit "
        "(`relief.reference.exact_hit`), over the rays not capped, **· mean fetches** per ray; then the share of "
        "rays flagged capped, where there are any. Settings: each ray-search technique's `accuracy_settings` "
        "(params: the overrides of its defaults).", "",
        *map_tables(rows), "",
        "## Self-shadowing", "",
        f"{shadow_sentence(shadows)} Each cell: **wrong hard state** from the technique's own view hit (% of rays, "
        "mean over the maps; the worst map in brackets) **/ mean soft difference · mean fetches per hard shadow "
        "ray**, against the float64 shadow of the exact hit (`relief.reference.shadow`).", "",
        *shadow_table(shadows),
    ]
