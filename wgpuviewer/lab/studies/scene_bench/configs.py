"""The scene benchmark's configurations: the baseline, the exact tracer, the configurations compared with it and the
goal's two. A configuration naming a parameter its technique lacks, or a technique not registered, is left out
(``configs``): the lists run on every checkout.
"""

from __future__ import annotations

from wgpuviewer.core.params import resolve_params
from wgpuviewer.lab.bench.run import params_label
from wgpuviewer.techniques import TECHNIQUES

BASELINE = ("basic", {})
#: The exact tracer (docs/techniques.md: maxmip walks the max pyramid to the exact first hit), with a step cap no
#: ray of these scenes reaches, so it is the reference everywhere (a capped ray's pixels are left out).
EXACT = ("maxmip", {"max_steps": 65536})
#: The configurations compared with it. auto at its texel budget alone asks max_error_px = 0 (off) where the
#: parameter exists and its defaults where not; duplicates after resolving are drawn once.
CONFIGS = (
    ("pom", {"layers": 8}), ("pom", {"layers": 16}), ("pom", {"layers": 24}), ("pom", {"layers": 32}),
    ("auto", {"max_error_px": 0.0}), ("auto", {}), ("auto", {"max_error_px": 0.5}), ("auto", {"max_error_px": 1.0}),
    ("contact", {}), ("relief", {}), ("steep", {}),
)
SMOKE_CONFIGS = (("pom", {"layers": 8}), ("relief", {}))
#: The goal's two configurations: auto at a 0.5-pixel budget against POM with 24 layers.
GOAL = (("auto", {"max_error_px": 0.5}), ("pom", {"layers": 24}))
GOAL_FETCH_RATIO = 0.5


def configs(wanted) -> list[tuple[str, dict]]:
    """(technique, every parameter value) of ``wanted`` that this checkout can draw, in order, each once."""
    out = []
    for name, overrides in wanted:
        technique = TECHNIQUES.get(name)
        if technique is None or not set(overrides) <= {p.name for p in technique.params}:
            continue
        config = (name, resolve_params(technique, overrides))
        if config not in out:
            out.append(config)
    return out


def config_key(name: str, values: dict) -> tuple[str, str]:
    """(technique, params) as results.csv writes them."""
    return name, params_label(values)


def goal_keys() -> tuple[tuple[str, str], ...] | None:
    """The goal's configurations as (technique, params), or None where one of them cannot be drawn here."""
    found = configs(GOAL)
    return tuple(config_key(*c) for c in found) if len(found) == len(GOAL) else None
