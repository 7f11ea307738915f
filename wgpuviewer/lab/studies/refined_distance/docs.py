"""The refined-distance study's generated blocks in docs/maps.md and docs/techniques.md, made from the committed run
(``benchmarks/refined_distance/``: results.csv's fetch counts of the numpy twin, formats.csv's bake times);
``wgpuviewer docs`` writes them (``wgpuviewer.lab.docs``).

- ``refined distance baseline`` (maps.md): the centre-sampled baseline's extra fetches over ``distance`` at 45-80°;
- ``refined distance bake times`` (maps.md): the plain and refined bakes' times per size and path;
- ``refined distance savings`` (techniques.md): the refined map's fetch savings against ``distance`` and the
  baseline, over the run's maps;
- ``refined distance worked example`` (maps.md): the paper's point C rebuilt (the bound's run,
  ``benchmarks/refined_distance/bounded/``: example.csv, worked_example.png);
- ``refined distance bounded`` (maps.md): per map class, what the exact-visibility bound saves and what the
  conservative cut gets of it (the bound's run: bounded.csv, bounded_maps.csv)."""

from __future__ import annotations

from collections import defaultdict
from pathlib import Path

from wgpuviewer.lab.harness.blocks import Block

from . import bounded, example
from .run import FORMATS_TABLE, TABLE

RUN = "benchmarks/refined_distance"
#: The bound's run (``--only bounded``): the worked example and the exact-visibility maps.
BOUND = f"{RUN}/bounded"
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
    r = example.TABLE.read(root / BOUND / "example.csv")[0]
    e = [float(x) for x in r["steps_euclidean"].split()]
    f = [float(x) for x in r["steps_refined"].split()]
    return (f"\nMeasured (`{BOUND}/example.csv`): Euclidean value {float(r['euclidean']):.3f} texels, refined value "
            f"{float(r['refined']):.3f} (the directions sampled every {example.POLAR_STEP:g}° of polar angle and "
            f"{example.AZIMUTH_STEP:g}° of azimuth: a sampled least free path lies above the exact one), V1's hit "
            f"{float(r['hit_v1']):.3f} texels on at {float(r['horizon']):.1f}°. Donnelly's loop along V1 steps "
            f"{', '.join(f'{x:.3f}' for x in e)} with the Euclidean values and {', '.join(f'{x:.3f}' for x in f)} "
            f"with the refined ones. The product's conservative cut lets rays up to {float(r['cut_single']):.1f}° "
            f"(single cone) and {float(r['cut_sectors']):.1f}° ({example.CUT_SECTORS[-1]} sectors, the one towards "
            f"A) reach C's voxel.\n\n![the worked example](../{BOUND}/{example.PLOT})\n")


def bounded_body(root: Path) -> str:
    rows = bounded.TABLE.read(root / BOUND / "bounded.csv")
    for r in rows:
        r["angle"], r["fetches_mean"], r["passed"] = float(r["angle"]), float(r["fetches_mean"]), float(r["passed"])
    maps = bounded.MAPS_TABLE.read(root / BOUND / "bounded_maps.csv")
    classes = bounded.by_class(rows)
    members = {c: sorted({r["heightmap"] for r in rows if r["class"] == c}) for c in classes}
    angles = sorted({r["angle"] for r in rows})

    def mean(c, v):
        return f"{100 * sum(classes[c][v]) / len(classes[c][v]):+.1f} %"

    lines = ["", f"The run's {rows[0]['size']} maps, views at {', '.join(f'{a:g}' for a in angles)}° (`{BOUND}/bounded.csv`; "
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


BLOCKS = (Block("docs/maps.md", "refined distance baseline", f"{RUN}/results.csv", baseline_body, results=RUN),
          Block("docs/maps.md", "refined distance bake times", f"{RUN}/formats.csv", bake_body, results=RUN),
          Block("docs/techniques.md", "refined distance savings", f"{RUN}/results.csv", savings_body, results=RUN),
          Block("docs/maps.md", "refined distance worked example", f"{BOUND}/example.csv", example_body, results=BOUND),
          Block("docs/maps.md", "refined distance bounded", f"{BOUND}/bounded.csv and {BOUND}/bounded_maps.csv",
                bounded_body, results=BOUND))
