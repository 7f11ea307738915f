"""docs/perspective.md's generated blocks, made from the committed runs; ``wgpuviewer docs`` writes them
(``wgpuviewer.lab.docs``). They compute from the committed CSVs and measure nothing.

From the full run (``benchmarks/perspective/``: results.csv, tieback.csv, threads.csv):

- ``perspective recommendation``: the cheapest method within the budget per regime and what the table means
  (``report.recommendation``, the report's own section);
- ``perspective answers``: the timings against ``direct``, the incremental drift against span length, the
  k-parallel and two-ended cuts, the mitigations, the approximations and large coordinates (``report.answers``);
- ``perspective drift``: the incremental drift against tilt and offset, and the float64 forms' against float32's
  (``drift_lines``);
- ``perspective tieback``: the relief techniques' hit error at large texture coordinates and where it passes a
  tenth of a texel (``tables.tieback_table``, ``tieback_limit``).
- ``perspective threads``: the parallel forms (k lanes, two ends) and whole spans timed on 1, 2 and all of the
  machine's threads beside the scalar and SIMD builds, the core count and the recommendation revisited
  (``threads_report.section``)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from wgpuviewer.lab.harness import suite as harness_suite
from wgpuviewer.lab.harness.blocks import Block

from . import threads_report
from .report import answers, recommendation
from .run import SUITES, TABLE, TIEBACK_TABLE
from .selection import _f, _finite, first_row, select_rows
from .tables import tieback_table
from .threaded import THREADS_TABLE

RUN = "benchmarks/perspective"
#: The tie-back's limit: a tenth of a texel of hit error.
TIEBACK_BOUND = 0.1


def _rows(root: Path) -> list[dict]:
    return TABLE.read(root / RUN / "results.csv")


def _software(rows: list[dict]) -> bool:
    """Whether the run's adapter is a software one (wgpu names those "(CPU)")."""
    return any("(CPU)" in (r["adapter"] or "") for r in rows)


def _incremental(rows, sweep: str, precision: str = "float32") -> list[dict]:
    return [r for r in select_rows(rows, sweep=sweep, method="incremental", precision=precision)
            if _finite(r["max_err_px"])]


def drift_lines(rows: list[dict]) -> list[str]:
    """The float32 incremental form's worst pixel against tilt and offset (``direct`` beside it at the largest
    offset), and how much less the float64 form drifts over the span lengths (median of the ratio, as a power of
    two)."""
    out = []
    # at and past the horizon (90°) pixels are flagged: those tilts say nothing about the drift
    tilts = sorted((r for r in _incremental(rows, "tilt") if r["tilt_deg"] < 90), key=lambda r: r["tilt_deg"])
    if tilts:
        out.append(f"- Against tilt (L = {tilts[0]['span_length']}, before the horizon): `incremental` "
                   + ", ".join(f"{_f(r['max_err_px'])} px at {r['tilt_deg']:g}°" for r in tilts)
                   + f"; in texels at {tilts[-1]['tilt_deg']:g}°: {_f(tilts[-1]['max_err'])}.")
    offsets = sorted((r for r in _incremental(rows, "magnitude") if r["offset_texels"] > 0),
                     key=lambda r: r["offset_texels"])
    if offsets:
        top = offsets[-1]
        direct = first_row(rows, sweep="magnitude", method="direct", precision="float32",
                           offset_texels=top["offset_texels"])
        out.append(f"- Against offset (L = {top['span_length']}): `incremental` "
                   + ", ".join(f"{_f(r['max_err_px'])} px at {r['offset_texels']:g} texels" for r in offsets)
                   + (f"; `direct` {_f(direct['max_err_px'])} px ({_f(direct['max_err'])} texels) at "
                      f"{top['offset_texels']:g}, where float32's spacing is "
                      f"{_f(float(np.spacing(np.float32(top['offset_texels']))))} texels" if direct else "") + ".")
    wide = {r["span_length"]: r["max_err_px"] for r in _incremental(rows, "span_length", "float64")}
    ratios = sorted(r["max_err_px"] / wide[r["span_length"]] for r in _incremental(rows, "span_length")
                    if wide.get(r["span_length"], 0) > 0)
    if ratios:
        median = ratios[len(ratios) // 2] if len(ratios) % 2 else (ratios[len(ratios) // 2 - 1]
                                                                  + ratios[len(ratios) // 2]) / 2
        out.append(f"- The float64 `incremental` drifts 2^{math.log2(median):.1f} times less than float32's (median "
                   f"of the ratio over {len(ratios)} span lengths).")
    return out


def tieback_limit(relief: list[dict], bound: float = TIEBACK_BOUND) -> str:
    """The largest magnitude M at which every technique's p99 hit error stays under ``bound`` texels, and the first
    at which one passes it."""
    worst = {}
    for r in relief:
        worst[r["magnitude_uv"]] = max(worst.get(r["magnitude_uv"], 0.0), r["p99_err"])
    below = [m for m in sorted(worst) if worst[m] < bound]
    above = [m for m in sorted(worst) if worst[m] >= bound]
    texels = relief[0]["texels"]
    text = f"On this {texels}-texel map every technique's p99 error"
    if below:
        text += f" stays under {bound:g} texel up to M = {below[-1]:g} (at most {_f(worst[below[-1]])} texels)"
    if above:
        text += (f"{' and' if below else ''} passes it at M = {above[0]:g} ({_f(worst[above[0]])}), i.e. |uv| × "
                 f"texture width must stay under about {above[0] * texels:g}")
    return text + "."


def recommendation_body(root: Path) -> str:
    return "\n".join(["", *recommendation(_rows(root)), ""])


def answers_body(root: Path) -> str:
    rows = _rows(root)
    suite = harness_suite.pick(SUITES, rows[0]["suite"])
    return "\n".join(["", *(f"- {a}" for a in answers(rows, suite, _software(rows))), ""])


def drift_body(root: Path) -> str:
    return "\n".join(["", *drift_lines(_rows(root)), ""])


def tieback_body(root: Path) -> str:
    relief = TIEBACK_TABLE.read(root / RUN / "tieback.csv")
    return "\n".join(["", f"`{RUN}/tieback.csv`, p99 hit-uv error in texels:", "", *tieback_table(relief), "",
                      tieback_limit(relief), ""])


def threads_body(root: Path) -> str:
    return "\n".join(["", *threads_report.section(THREADS_TABLE.read(root / RUN / threads_report.THREADS_FILE)),
                      ""])


BLOCKS = (Block("docs/perspective.md", "perspective recommendation", f"{RUN}/results.csv", recommendation_body,
                results=RUN),
          Block("docs/perspective.md", "perspective answers", f"{RUN}/results.csv", answers_body, results=RUN),
          Block("docs/perspective.md", "perspective drift", f"{RUN}/results.csv", drift_body, results=RUN),
          Block("docs/perspective.md", "perspective tieback", f"{RUN}/tieback.csv", tieback_body, results=RUN),
          Block("docs/perspective.md", "perspective threads", f"{RUN}/{threads_report.THREADS_FILE}",
                threads_body, results=RUN))
