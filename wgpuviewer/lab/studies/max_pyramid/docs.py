"""docs/max-pyramid.md's generated blocks, made from the committed run's CSV files (benchmarks/max_pyramid) with the
report's own tables; ``wgpuviewer docs`` writes them (``wgpuviewer.lab.docs``).

- ``max-pyramid claim``: the answer per relief class and walk, and the twin's agreement with the GPU probe;
- ``max-pyramid ratios``: maxmip's cost over the cheapest linear search's per map and angle, both criteria;
- ``max-pyramid levels``: steps per level, "at most 2 steps inside a parent", climbs;
- ``max-pyramid early exit``: the paper's early exit per map.
"""

from __future__ import annotations

from pathlib import Path

from wgpuviewer.lab.harness.blocks import Block

from .report import claim_table, early_exit_summary, level_table, ratio_table, twin_line
from .tables import LEVELS_TABLE, TABLE

RUN = "benchmarks/max_pyramid"
PAGE = "docs/max-pyramid.md"


def _rows(root: Path) -> list[dict]:
    return TABLE.read(root / RUN / "results.csv")


def claim_body(root: Path) -> str:
    return "\n".join(["", *claim_table(_rows(root)), "", twin_line(_rows(root)), ""])


def ratios_body(root: Path) -> str:
    rows = _rows(root)
    return "\n".join(["", "At p95 ≤ 0.25 texel:", "", *ratio_table(rows, "p95"), "", "At max ≤ 1 texel:", "",
                      *ratio_table(rows, "max"), ""])


def levels_body(root: Path) -> str:
    return "\n".join(["", *level_table(LEVELS_TABLE.read(root / RUN / "levels.csv"), _rows(root)), ""])


def early_exit_body(root: Path) -> str:
    return "\n".join(["", *early_exit_summary(_rows(root)), ""])


BLOCKS = (
    Block(PAGE, "max-pyramid claim", f"{RUN}/results.csv", claim_body, results=RUN),
    Block(PAGE, "max-pyramid ratios", f"{RUN}/results.csv", ratios_body, results=RUN),
    Block(PAGE, "max-pyramid levels", f"{RUN}/levels.csv and results.csv", levels_body, results=RUN),
    Block(PAGE, "max-pyramid early exit", f"{RUN}/results.csv", early_exit_body, results=RUN),
)
