"""docs/shadows.md's generated blocks: ``shadows results``, the committed run's tables, made from its results.csv and
timing.csv by the report's own code (``run.report``, its header left out); ``shadows hidden``, the share of the floor
the timing's wall hides (timing.csv's ``hidden``). ``wgpuviewer docs`` writes them (``wgpuviewer.lab.docs``)."""

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


def hidden_line(times: list[dict]) -> str:
    """The share of the floor's pixels the occluded scene's wall hides (the same in every row of that scene)."""
    shares = sorted({r["hidden"] for r in times if r["scene"] == "occluded"})
    if not shares:
        return "The run timed no occluded scene."
    share = f"{shares[0]:.0%}" if len(shares) == 1 else f"{shares[0]:.0%}-{shares[-1]:.0%}"
    return f"The wall hides {share} of the floor's pixels (`{RUN}/timing.csv`, `hidden`)."


def hidden_body(root: Path) -> str:
    return "\n" + hidden_line(TIMING.read(root / RUN / "timing.csv")) + "\n"


BLOCKS = (Block("docs/shadows.md", "shadows hidden", f"{RUN}/timing.csv", hidden_body, results=RUN),
          Block("docs/shadows.md", "shadows results", f"{RUN}/results.csv and timing.csv", body, results=RUN),)
