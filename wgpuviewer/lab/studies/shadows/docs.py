"""docs/shadows.md's generated block (``<!-- generated: shadows results -->``): the committed run's tables, made from
its results.csv and timing.csv by the report's own code (``run.report``, its header left out); ``wgpuviewer docs``
writes it (``wgpuviewer.lab.docs``)."""

from __future__ import annotations

from pathlib import Path

from wgpuviewer.lab.harness import suite as harness_suite
from wgpuviewer.lab.harness.blocks import Block
from wgpuviewer.lab.harness.header import Header

from .run import RESULTS, SUITES, TIMING, TITLE, report

RUN = "benchmarks/shadows"
PICTURE = "shadows.png"


def body(root: Path) -> str:
    rows = RESULTS.read(root / RUN / "results.csv")
    times = TIMING.read(root / RUN / "timing.csv")
    header = Header(TITLE, "", "", "full", None, None)
    text = report(header, rows, f"../{RUN}/{PICTURE}", harness_suite.pick(SUITES, "full"), times)
    own = text[text.index("- rays:"):]  # after the header's fields: the page names the run itself
    return own.strip()


BLOCKS = (Block("docs/shadows.md", "shadows results", f"{RUN}/results.csv and timing.csv", body, results=RUN),)
