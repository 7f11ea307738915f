"""The filtering study's aggregation of results.csv rows, shared by its report, docs block and pictures: the
ranked rows, rows by configuration, per-case differences between configurations, means and their formatting."""

from __future__ import annotations

import math
from collections import defaultdict

import numpy as np

from .suites import EXACT, Config


def _finite(values) -> list[float]:
    return [float(v) for v in values if isinstance(v, (int, float)) and math.isfinite(v)]


def _mean(values) -> float:
    values = _finite(values)
    return float(np.mean(values)) if values else float("nan")


def _geomean(values) -> float:
    values = [v for v in _finite(values) if v > 0]
    return float(np.exp(np.mean(np.log(values)))) if values else float("nan")


def ranked(rows: list[dict]) -> list[dict]:
    """The rows that rank the filters: ranked cases, valid measurements."""
    return [r for r in rows if r["role"] == "rank" and not r["void"]]


def by_config(rows: list[dict]) -> dict[str, list[dict]]:
    groups = defaultdict(list)
    for row in rows:
        groups[row["label"]].append(row)
    return groups


def label(filter_name: str, source: str, params: str = "", tracer: str = EXACT) -> str:
    return f"{filter_name}{' ' + params if params else ''} ({source})" + ("" if tracer == EXACT else f" [{tracer}]")


def _baseline_label(row: dict, config: Config) -> str:
    return config.on(row["tracer"]).label


def differences(rows: list[dict], a: str, b: str, key: str = "psnr") -> list[float]:
    """Per case, row[key](label a) - row[key](label b), over the cases with both."""
    per_case = defaultdict(dict)
    for row in rows:
        per_case[row["case"]][row["label"]] = row[key]
    return [c[a] - c[b] for c in per_case.values() if a in c and b in c and math.isfinite(c[a] - c[b])]


def against(rows: list[dict], config: Config) -> dict[str, list[float]]:
    """label -> per-case PSNR differences against ``config`` on the label's own tracer."""
    out = {}
    for name, group in by_config(rows).items():
        base = _baseline_label(group[0], config)
        if name != base:
            out[name] = differences(rows, name, base)
    return out


def _fmt(v: float, spec: str = "+.2f") -> str:
    return "–" if not math.isfinite(v) else format(v, spec)


FOLLOWS = ("own", "masked")  # the albedos that follow the relief


def beyond_uncertainty(group: list[dict], rows: list[dict], other: str) -> tuple[int, int]:
    """How many rows of ``group`` beat, and lose to, the row labelled ``other`` of the same case in ``rows`` by more
    than both rows' reference uncertainty."""
    by_case = {r["case"]: r for r in rows if r["label"] == other}
    pairs = [(r, by_case[r["case"]]) for r in group if r["case"] in by_case]
    margins = [(a["psnr"] - b["psnr"], a["psnr_uncertainty"] + b["psnr_uncertainty"]) for a, b in pairs]
    return sum(d > m for d, m in margins), sum(-d > m for d, m in margins)
