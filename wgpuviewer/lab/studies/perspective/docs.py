"""docs/perspective.md's generated block made from the committed threaded run (``benchmarks/perspective_threads/
threads.csv``); ``wgpuviewer docs`` writes it (``wgpuviewer.lab.docs``).

- ``perspective threads``: the parallel forms (k lanes, two ends) and whole spans timed on 1, 2 and all of the
  machine's threads beside the scalar and SIMD builds, the core count and the recommendation revisited
  (``threads_report.section``)."""

from __future__ import annotations

from pathlib import Path

from wgpuviewer.lab.harness.blocks import Block

from . import threads_report
from .threaded import THREADS_TABLE

RUN = "benchmarks/perspective_threads"


def threads_body(root: Path) -> str:
    return "\n".join(["", *threads_report.section(THREADS_TABLE.read(root / RUN / threads_report.THREADS_FILE)), ""])


BLOCKS = (Block("docs/perspective.md", "perspective threads", f"{RUN}/{threads_report.THREADS_FILE}", threads_body,
                results=RUN),)
