"""docs/filtering.md's generated blocks: the numbers the page quotes, made from the committed runs' results.csv and
run.json with the report's own tables; ``wgpuviewer docs`` writes them (``wgpuviewer.lab.docs``).

- ``filtering results``: the main run's recommendation, sources, visibility, weighting, flicker, tuning, measures;
- ``filtering runs``: what each committed run covers (its command, cases, duration, adapter);
- ``filtering angles``: the other-angles run's recommendation table;
- ``filtering by relief``: the per-relief verdict with per-case signs and bootstrap intervals, and the row-ends
  method against the full one, over every committed run;
- ``ewa alpha``: EWA's default alpha, from the filter registry."""

from __future__ import annotations

import json
from pathlib import Path

from wgpuviewer.lab.harness.blocks import Block
from wgpuviewer.relief.filters import get_filter

from .byrelief import merged, section
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
ANGLES_RUN = "benchmarks/filtering_angles"
RELIEFS_RUN = "benchmarks/filtering_reliefs"  # the flat relief and the brick photograph
RUNS = (FILTERING_RUN, ANGLES_RUN, RELIEFS_RUN)


def _rows(root: Path, run: str) -> list[dict]:
    return TABLE.read(root / run / "results.csv")


def committed(root: Path) -> list[str]:
    """RUNS whose results are in the checkout (a run still measuring is left out until it has written them)."""
    return [run for run in RUNS if (root / run / "results.csv").is_file() and (root / run / RUN_FILE).is_file()]


def runs_body(root: Path) -> str:
    """One line per committed run: its command, ranked cases, configurations, duration and adapter."""
    lines = [""]
    for run in committed(root):
        record = json.loads((root / run / RUN_FILE).read_text())
        cases = {r["case"] for r in _rows(root, run) if r["role"] == "rank"}
        lines.append(f"- [`{run}/`](../{run}/report.md): `{record['command']}`: {len(cases)} ranked cases x "
                     f"{record['configs']} configurations, {record['tuning_cases']} tuning cases, "
                     f"{record['seconds'] / 60:.0f} minutes on {record['adapter']}.")
    return "\n".join(lines + [""])


def angles_body(root: Path) -> str:
    return "\n".join(["", *recommendation(_rows(root, ANGLES_RUN)), ""])


def by_relief_body(root: Path) -> str:
    return "\n".join(["", *section(merged({run.rsplit("_", 1)[-1]: _rows(root, run) for run in committed(root)})), ""])


def alpha_body(root: Path) -> str:
    return f"\nEWA's default: `alpha = {get_filter('ewa').defaults()['alpha']:g}` (`wgpuviewer/relief/filters.py`).\n"


PAGE = "docs/filtering.md"
BLOCKS = (Block(PAGE, "filtering results", f"{FILTERING_RUN}/results.csv",
                lambda root: docs_body_of(root / FILTERING_RUN), results=FILTERING_RUN),
          Block(PAGE, "filtering runs", "every committed filtering run's run.json and results.csv", runs_body,
                results=FILTERING_RUN),
          Block(PAGE, "filtering angles", f"{ANGLES_RUN}/results.csv", angles_body, results=ANGLES_RUN),
          Block(PAGE, "filtering by relief", "every committed filtering run's results.csv", by_relief_body,
                results=FILTERING_RUN),
          Block(PAGE, "ewa alpha", "the filter registry (ewa's defaults)", alpha_body))
