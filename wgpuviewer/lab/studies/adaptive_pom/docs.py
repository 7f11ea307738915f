"""docs/benchmarks.md's generated block (``<!-- generated: adaptive pom -->``): the answer to the thesis' question
(adaptive POM against POM at equal error) made from the committed run's results.csv and comparison.csv with the
report's own tables; ``wgpuviewer docs`` writes it (``wgpuviewer.lab.docs``)."""

from __future__ import annotations

from pathlib import Path

from wgpuviewer.lab.harness.blocks import Block

from .compare import MAX_ANGLE, MEANINGFUL_P95, TEXTURED, pom_cost_at
from .compare import TABLE as COMPARISON
from .measure import DEGENERATE, TABLE
from .report import MAIN, PICTURE, _n, brick_lines, per_map, summary

RUN = "benchmarks/adaptive_pom"


def answer(comparison: list[dict]) -> str:
    """The answer in words: the thesis' setting on the textured maps, the cheapest and the dearest setting."""
    textured = [r for r in comparison if r["heightmap"] == TEXTURED and r["ratio"] is not None]
    main = next(r for r in textured if r["config"] == MAIN)
    best = min(textured, key=lambda r: r["ratio"])
    worst = max(textured, key=lambda r: r["ratio"])
    signs = [r for r in comparison if r["config"] == MAIN and r["heightmap"] != TEXTURED and not r["degenerate"]]
    count = {v: sum(r["verdict"] == v for r in signs) for v in ("adaptive cheaper", "POM cheaper", "no clear difference")}
    return (f"**Answer.** At equal p95 error, `{MAIN}` (the thesis' setting) takes {_n(main['ratio'])}× POM's SIMD-tile "
            f"fetches on the textured maps (95 % interval {_n(main['low'])}-{_n(main['high'])}: {main['verdict']}); "
            f"per map it is cheaper on {count['adaptive cheaper']}, dearer on {count['POM cheaper']} and not clearly "
            f"either on {count['no clear difference']} of {len(signs)} textured maps. Across the sweep the ratio runs "
            f"from {_n(best['ratio'])}× (`{best['config']}`) to {_n(worst['ratio'])}× (`{worst['config']}`).")


def detail_claim(rows: list[dict], heightmap: str = "brick") -> str:
    """The thesis' claim of detail comparable to POM 32, in numbers: adaptive 4-32's p95 over POM 32's per angle."""
    pick = {(r["config"], r["angle"]): r["p95"] for r in rows if r["heightmap"] == heightmap}
    parts = [f"{pick[(MAIN, a)] / pick[('pom 32', a)]:.1f}× at {a:g}°" for (c, a) in pick
             if c == MAIN and 0 < a <= MAX_ANGLE and pick.get(("pom 32", a), 0) > 0]
    return (f"On {heightmap}, `{MAIN}`'s p95 is " + ", ".join(parts) + " POM 32's." if parts else "")


def body(root: Path) -> str:
    rows = TABLE.read(root / RUN / "results.csv")
    comparison = COMPARISON.read(root / RUN / "comparison.csv")
    return "\n".join([answer(comparison), "", "Every adaptive setting on the textured maps together:", "",
                      *summary(comparison), "", "Per map, the thesis' setting (the degenerate maps apart):", "",
                      *per_map(comparison), "", "The thesis' claim of detail comparable to POM 32, on brick:", "",
                      *brick_lines(rows), "", detail_claim(rows), "",
                      f"![p95, p99 and max error against SIMD-tile fetches](../{RUN}/{PICTURE})"])


def time_body(root: Path, run: str) -> str:
    """adaptive 4-32's time against POM's at equal p95 in a bench run (measured side by side): POM's time at the
    adaptive p95 interpolated on POM's layer sweep, as the fetches are above."""
    import numpy as np

    from wgpuviewer.lab.bench.docs import missing
    from wgpuviewer.lab.bench.run import TABLE as BENCH

    if missing(root, run):
        return missing(root, run)
    rows = BENCH.read(root / run / "results.csv")
    ratios, left_out = [], 0
    for (name, angle) in dict.fromkeys((r["heightmap"], r["angle"]) for r in rows):
        if name in DEGENERATE or not 0 < angle <= MAX_ANGLE:
            continue
        view = [r for r in rows if (r["heightmap"], r["angle"]) == (name, angle)]
        pom = [r for r in view if r["technique"] == "pom"]
        adaptive = next((r for r in view if r["technique"] == "pom_adaptive" and r["params"] == BENCH_ADAPTIVE), None)
        if adaptive is None or not pom or not adaptive["uv_err_p95"] <= MEANINGFUL_P95:
            left_out += adaptive is not None
            continue
        cost, _ = pom_cost_at(np.array([r["uv_err_p95"] for r in pom]), np.array([r["ratio_to_basic"] for r in pom]),
                              adaptive["uv_err_p95"])
        if np.isfinite(cost):
            ratios.append(adaptive["ratio_to_basic"] / cost)
        else:
            left_out += 1
    if not ratios:
        return f"No view of `{run}/` has both `pom_adaptive` ({BENCH_ADAPTIVE}) and POM within reach."
    mean = float(np.exp(np.mean(np.log(ratios))))
    adapter = rows[0]["adapter"]
    kind = "a software adapter: its ratios are not a GPU's" if "(CPU)" in adapter else "a GPU"
    return (f"Time, measured side by side (`{run}/`, {adapter}, {kind}): at equal "
            f"p95, `{MAIN}` takes {_n(mean)}× POM's time (geometric mean over {len(ratios)} textured-map views at "
            f"30-{MAX_ANGLE:g}°, range {_n(min(ratios))}-{_n(max(ratios))}; {left_out} view{'s' * (left_out != 1)} "
            f"left out: adaptive p95 above {MEANINGFUL_P95:g} texel or beyond POM's sweep).")


BENCH_RUN = "benchmarks/llvmpipe-reduced/bench"
H100_RUN = "benchmarks/h100"
BENCH_ADAPTIVE = "min_layers=4 max_layers=32 angle_only=false"  # bench's pom_adaptive row (the defaults)
BLOCKS = (Block("docs/benchmarks.md", "adaptive pom", f"{RUN}/comparison.csv and results.csv", body, results=RUN),
          Block("docs/benchmarks.md", "adaptive pom time", f"{BENCH_RUN}/results.csv",
                lambda root: time_body(root, BENCH_RUN), results=BENCH_RUN),
          Block("docs/benchmarks.md", "adaptive pom time h100", f"{H100_RUN}/results.csv",
                lambda root: time_body(root, H100_RUN), results=H100_RUN))
