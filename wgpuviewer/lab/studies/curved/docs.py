"""docs/curved.md's generated blocks: ``curved results``, the committed run's tables (the rule's κ per map, the S/R
limits, the error by angle and S/R, the techniques against the curved truth), made from its results.csv by the
report's own code (``run.report``, its header left out, its headings one level down); ``curved rule limits``, the
largest S/R the first-order rule allows for a budget at the run's relief depths (``rule_limits``). ``wgpuviewer docs``
writes them (``wgpuviewer.lab.docs``)."""

from __future__ import annotations

from pathlib import Path

from wgpuviewer.lab.harness.blocks import Block
from wgpuviewer.lab.harness.header import Header

from .run import TABLE, TITLE, first_order, report

RUN = "benchmarks/curved"
#: The rule's worked budget (texels) and view angles (degrees).
RULE_BUDGET = 0.5
RULE_ANGLES = (60.0, 75.0, 85.0)


def body(root: Path) -> str:
    rows = TABLE.read(root / RUN / "results.csv")
    text = report(rows, Header(TITLE, "", "", "full", None, None), plotted=False)
    tables = text[text.index("## The rule"):]
    return "\n".join("#" + line if line.startswith("#") else line for line in tables.splitlines()).strip()


def rule_limits(depths, budget: float = RULE_BUDGET, angles=RULE_ANGLES) -> str:
    """The largest S/R with the first-order error (``run.first_order``) within ``budget`` texels, per relief depth
    (texels) and angle."""
    cells = [f"{a:g}°: " + ", ".join(f"{budget / first_order(a, d, 1.0):.2g} ({d:g} texels deep)" for d in depths)
             for a in angles]
    return f"For {budget:g} texel the rule allows S/R up to " + "; ".join(cells) + "."


def limits_body(root: Path) -> str:
    depths = sorted({r["depth_texels"] for r in TABLE.read(root / RUN / "results.csv")}, reverse=True)
    return "\n" + rule_limits(depths)[:-1] + f" (the relief depths of `{RUN}/results.csv`).\n"


BLOCKS = (Block("docs/curved.md", "curved rule limits", f"{RUN}/results.csv", limits_body, results=RUN),
          Block("docs/curved.md", "curved results", f"{RUN}/results.csv", body, results=RUN),)
