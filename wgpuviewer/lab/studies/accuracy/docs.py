"""docs/accuracy.md's generated blocks, made from the committed run (``benchmarks/accuracy``) with the report's own
tables; ``wgpuviewer docs`` writes them (``wgpuviewer.lab.docs``).

- ``accuracy run``: the run's command, adapter, date and duration (its ``stamp.json``) and what it measured with;
- ``accuracy tables``: one table per height map (results.csv);
- ``accuracy self-shadowing``: the self-shadowing table (shadows.csv).
"""

from __future__ import annotations

from pathlib import Path

from wgpuviewer.lab.harness import stamp
from wgpuviewer.lab.harness.blocks import Block

from .report import facts, map_tables, shadow_sentence, shadow_table
from .run import RESULTS, SHADOWS

RUN = "benchmarks/accuracy"
PAGE = "docs/accuracy.md"


def run_body(root: Path) -> str:
    rows = RESULTS.read(root / RUN / "results.csv")
    record = stamp.read(root / RUN)
    if record is None:
        what = f"A run whose command, adapter and date are unknown (`{RUN}/` has no {stamp.STAMP})"
    else:
        what = (f"`{record['command']}` on {record['adapter']}, {record['date'][:10]}, "
                f"{record['seconds'] / 60:.1f} minutes")
    return f"\n{what}: {facts(rows)}. Its report: [`{RUN}/report.md`](../{RUN}/report.md).\n"


def tables_body(root: Path) -> str:
    return "\n".join(["", *map_tables(RESULTS.read(root / RUN / "results.csv")), ""])


def shadows_body(root: Path) -> str:
    rows = SHADOWS.read(root / RUN / "shadows.csv")
    return "\n".join(["", shadow_sentence(rows), "", *shadow_table(rows), ""])


BLOCKS = (
    Block(PAGE, "accuracy run", f"{RUN}/stamp.json and results.csv", run_body, results=RUN),
    Block(PAGE, "accuracy tables", f"{RUN}/results.csv", tables_body, results=RUN),
    Block(PAGE, "accuracy self-shadowing", f"{RUN}/shadows.csv", shadows_body, results=RUN),
)
