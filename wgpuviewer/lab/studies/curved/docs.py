"""docs/curved.md's generated block (``<!-- generated: curved results -->``): the committed run's tables (the rule's
κ per map, the S/R limits, the error by angle and S/R, the techniques against the curved truth), made from its
results.csv by the report's own code (``run.report``, its header left out, its headings one level down); ``wgpuviewer
docs`` writes it (``wgpuviewer.lab.docs``)."""

from __future__ import annotations

from pathlib import Path

from wgpuviewer.lab.harness.blocks import Block
from wgpuviewer.lab.harness.header import Header

from .run import TABLE, TITLE, report

RUN = "benchmarks/curved"


def body(root: Path) -> str:
    rows = TABLE.read(root / RUN / "results.csv")
    text = report(rows, Header(TITLE, "", "", "full", None, None), plotted=False)
    tables = text[text.index("## The rule"):]
    return "\n".join("#" + line if line.startswith("#") else line for line in tables.splitlines()).strip()


BLOCKS = (Block("docs/curved.md", "curved results", f"{RUN}/results.csv", body, results=RUN),)
