"""docs/techniques.md's generated block ``contact vs relief``: the contact study's tables, made from the committed
run in ``benchmarks/contact_vs_relief``; ``wgpuviewer docs`` writes it (``wgpuviewer.lab.docs``)."""

from __future__ import annotations

from pathlib import Path

from wgpuviewer.lab.harness.blocks import Block

from .report import report
from .run import RESULTS

CONTACT_RUN = "benchmarks/contact_vs_relief"


def docs_body(root: Path) -> str:
    return "\n".join(["", *report(RESULTS.read(root / CONTACT_RUN / "results.csv")), ""])


BLOCKS = (Block("docs/techniques.md", "contact vs relief", f"{CONTACT_RUN}/results.csv", docs_body,
                results=CONTACT_RUN),)
