"""docs/benchmarks.md's generated block of the scene benchmark (``<!-- generated: scene bench -->``): the goal's
figures per scene and every configuration's SIMD-tile fetches, FLIP and p95 pixel error per scene, made from a
committed run's results.csv with the report's own aggregation; ``wgpuviewer docs`` writes it
(``wgpuviewer.lab.docs``)."""

from __future__ import annotations

from pathlib import Path

from wgpuviewer.lab.harness.blocks import Block

from .report import aggregate, goal_lines, label
from .run import RESULTS

SCENE_BENCH_RUN = "benchmarks/scene_bench"


def docs_body(rows: list[dict]) -> str:
    """The goal's table, then per configuration and scene: SIMD-tile fetches / FLIP / p95 hit error in pixels."""
    table = aggregate(rows)
    scenes = list(table)
    sizes = sorted({r["size"] for r in rows})
    views = list(dict.fromkeys(r["view"] for r in rows))
    configs = list(dict.fromkeys((r["technique"], r["params"]) for r in rows))
    lines = ["", f"Frame {', '.join(sizes)}; views {', '.join(views)}; means over the views of each scene.", "",
             *goal_lines(table), "",
             "Per configuration and scene: SIMD-tile fetches / FLIP / p95 hit error in pixels:", "",
             "| configuration | " + " | ".join(scenes) + " |", "|---|" + "---|" * len(scenes)]
    for key in configs:
        cells = []
        for scene in scenes:
            m = table[scene].get(key)
            cells.append("–" if m is None else
                         f"{m['fetches_simd']:.1f} / {m['flip_mean']:.4f} / {m['px_err_p95']:.2f}")
        lines.append(f"| `{label(key)}` | " + " | ".join(cells) + " |")
    return "\n".join(lines + [""])


def docs_body_of(folder: Path) -> str:
    return docs_body(RESULTS.read(Path(folder) / "results.csv"))


BLOCKS = (Block("docs/benchmarks.md", "scene bench", f"{SCENE_BENCH_RUN}/results.csv",
                lambda root: docs_body_of(root / SCENE_BENCH_RUN), results=SCENE_BENCH_RUN),)
