"""The hard cases the compiled loops' and the WGSL kernels' tests both hold to their numpy twins: spans at a
10^6-texel offset, 89.9 degrees on an NPOT span, past the horizon, and 1-, 2- and 63-pixel spans."""

from __future__ import annotations

import numpy as np

from wgpuviewer.lab.studies.perspective import geometry as g


def hard_cases(seed: int, random_spans: int, grazing_rows: int):
    """(label, quad, spans) of each case; ``random_spans`` spans drawn with ``seed`` at the offset."""
    rng = np.random.default_rng(seed)
    wide = g.build(g.Setup(span_length=2000, rows=24, tilt=80.0, offset=1e6))
    yield ("1e6 offset, random spans", wide,
           g.Spans(rng.integers(0, 1000, random_spans), rng.integers(0, 24, random_spans), 777))
    grazing = g.build(g.Setup(span_length=343, rows=grazing_rows, tilt=89.9))
    yield "89.9 degrees, NPOT", grazing, grazing.spans
    crossing = g.build(g.Setup(span_length=401, rows=3, tilt=95.0))
    yield "past the horizon", crossing, crossing.spans
    for length in (1, 2, 63):
        short = g.build(g.Setup(span_length=length, rows=2, tilt=60.0))
        yield f"{length}-pixel spans", short, short.spans
