"""The threaded timing's rows (``measure_suite``; ``threads_only.run_threads`` is ``wgpuviewer perspective
--threads-only``, threads.csv and a report.md of its own) and the section the full report and docs/perspective.md's
block give (``section``): per method and placement, the time per texel at 1, 2 and all threads as a multiple of the
scalar build's ``direct``, the speed-up over one thread, with the machine's core count and the revisited
recommendation."""

from __future__ import annotations

TITLE = "Perspective texturing: the paper's parallel forms on real threads"
THREADS_FILE = "threads.csv"


def _by(rows: list[dict]) -> dict[tuple[str, str, int], dict]:
    return {(r["method"], r["placement"], r["threads"]): r for r in rows}


def table(rows: list[dict]) -> list[str]:
    counts = sorted({r["threads"] for r in rows if r["placement"] in ("lanes", "spans")})
    head = " | ".join(f"{t} thread{'s' if t > 1 else ''}: x scalar direct (speed-up)" for t in counts)
    lines = [f"| method | scalar build | SIMD build | placement | {head} | bit-identical |",
             "|---|---|---|---|" + "---|" * len(counts) + "---|"]
    by = _by(rows)
    for method in dict.fromkeys(r["method"] for r in rows):
        scalar, simd = by.get((method, "scalar", 1)), by.get((method, "simd", 1))
        for placement in ("spans", "lanes"):
            cells = [by.get((method, placement, t)) for t in counts]
            if not any(cells):
                continue
            timed = " | ".join(f"{c['ratio_scalar_direct']:.2f} ({c['speedup']:.2f}x)" if c else "–" for c in cells)
            same = all(c["identical"] for c in cells if c)
            lines.append(f"| `{method}` | {scalar['ratio_scalar_direct']:.2f} | {simd['ratio_scalar_direct']:.2f} | "
                         f"{placement} | {timed} | {'yes' if same else 'no'} |")
    return lines


def findings(rows: list[dict]) -> list[str]:
    """The answers in words, each number from the rows."""
    by = _by(rows)
    most = max(r["threads"] for r in rows)
    cores = rows[0]["cores"]
    lanes = [r for r in rows if r["placement"] == "lanes" and r["threads"] == most]
    spans = [r for r in rows if r["placement"] == "spans" and r["threads"] == most]
    best_lanes = min(lanes, key=lambda r: r["ratio_scalar_direct"])
    best_spans = min(spans, key=lambda r: r["ratio_scalar_direct"])
    direct_spans = by[("direct", "spans", most)]
    simd = by[("direct", "simd", 1)]
    beats = [r["method"] for r in lanes if r["ratio_scalar_direct"] < direct_spans["ratio_scalar_direct"]]
    return [
        f"- Machine: {cores} logical CPUs; threads timed: {', '.join(str(t) for t in sorted({r['threads'] for r in rows}))}"
        f" (numba's default is all of them).",
        f"- The paper's placement (a span's lanes or ends on threads), {most} threads: best `{best_lanes['method']}` at "
        f"{best_lanes['ratio_scalar_direct']:.2f}x the scalar `direct` ({best_lanes['speedup']:.2f}x its own 1-thread "
        f"time). Spans on threads, {most} threads: best `{best_spans['method']}` at "
        f"{best_spans['ratio_scalar_direct']:.2f}x; `direct` {direct_spans['ratio_scalar_direct']:.2f}x "
        f"({direct_spans['speedup']:.2f}x its 1-thread time); the SIMD build's `direct` on one thread "
        f"{simd['ratio_scalar_direct']:.2f}x.",
        f"- Lanes-on-threads forms faster than `direct` with spans on the same {most} threads: "
        f"{', '.join(f'`{m}`' for m in beats) if beats else 'none'}.",
    ]


def section(rows: list[dict]) -> list[str]:
    if not rows:
        return ["Not timed in this suite (the full suite and `--threads-only` time it)."]
    r0 = rows[0]
    return [f"Compiled float32 loops (scalar builds: the threads are the only parallelism) on {r0['spans']} spans of "
            f"{r0['span_length']} pixels (tilt 80°), per texel as a multiple of the single-threaded scalar build's "
            "`direct` in the same round; speed-up: over the same loop on one thread. `lanes`: the paper's placement, "
            "a span's k lanes (or two ends) on threads; `spans`: the spans shared out among the threads, each "
            "walked by the method's own loop.", "", *findings(rows), "", *table(rows)]


def measure_suite(suite, quad) -> list[dict]:
    """threads.csv's rows on ``quad`` (the suite's first speed frame), with the suite's compiled loops' repeats and
    sample time; none in the smoke suite (compiling the threaded loops alone would outlast it; the unit tests run
    them)."""
    if suite.name == "smoke":
        return []
    from .threaded import measure

    return measure(quad.coefficients, quad.spans, suite.compiled_repeats, suite.compiled_sample_s)
