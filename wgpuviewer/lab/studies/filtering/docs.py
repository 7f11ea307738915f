"""docs/filtering.md's generated block (``<!-- generated: filtering results -->``): the numbers the page quotes,
made from a committed run's results.csv and run.json with the report's own tables; ``wgpuviewer docs`` writes it
(``wgpuviewer.lab.docs``)."""

from __future__ import annotations

import json
from pathlib import Path

from wgpuviewer.lab.harness.blocks import Block

from .report import derivative_sources, flicker, measures, recommendation, tuning, visibility, weighting
from .suites import RUN_FILE, TABLE

DOCS_BEGIN = "<!-- generated: filtering results -->"
DOCS_END = "<!-- end generated -->"


def docs_body(rows: list[dict], record: dict) -> str:
    """The block's text between its markers: the recommendation, EWA by derivative source, visibility, the
    weighting, flicker, tuning and the reference's measures."""
    void_labels = sorted({r["label"] for r in rows if r["void"]})
    lines = ["", *recommendation(rows), "", "Plain EWA by derivative source (exact tracer):", "",
             *derivative_sources(rows), "", "Visibility against plain EWA on the same footprint:", "",
             *visibility(rows), "", *weighting(rows), "", *flicker(rows), "", *tuning(rows), "",
             *measures(rows, record.get("reference", 16)), ""]
    if void_labels:
        lines += [f"Void on this adapter (in results.csv, in no aggregate): {', '.join(f'`{v}`' for v in void_labels)}"
                  f". {' '.join(record.get('void_notes', []))}", ""]
    return "\n".join(lines)


def docs_block(rows: list[dict], record: dict) -> str:
    """The block with its markers, as docs/filtering.md holds it."""
    return f"{DOCS_BEGIN}\n{docs_body(rows, record)}\n{DOCS_END}"


def docs_body_of(folder: Path) -> str:
    """``docs_body`` of the run in ``folder`` (its results.csv and run.json)."""
    return docs_body(TABLE.read(Path(folder) / "results.csv"), json.loads((Path(folder) / RUN_FILE).read_text()))


def docs_block_of(folder: Path) -> str:
    """``docs_block`` of the run in ``folder``."""
    return f"{DOCS_BEGIN}\n{docs_body_of(folder)}\n{DOCS_END}"


FILTERING_RUN = "benchmarks/filtering_lavapipe"
BLOCKS = (Block("docs/filtering.md", "filtering results", f"{FILTERING_RUN}/results.csv",
                lambda root: docs_body_of(root / FILTERING_RUN), results=FILTERING_RUN),)
