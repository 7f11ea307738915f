"""The perspective study's rows as its report and plots read them: the method groups, the error budgets, one
row or all rows matching some columns, a method's single precision, the speed frames, number formatting and the
power fit of error against span length."""

from __future__ import annotations

import math

import numpy as np

from .methods import METHODS, PARALLEL_THREADS

PAPER_F32 = ["direct", "span", "incremental", *(f"parallel_{k}" for k in PARALLEL_THREADS), "two_ended"]
RECIPROCAL = [m.name for m in METHODS.values() if m.family == "reciprocal"]
APPROXIMATIONS = [m.name for m in METHODS.values() if m.family == "approximation"]
MITIGATIONS = [m.name for m in METHODS.values() if m.family == "mitigation"]
#: The largest error (screen pixels, worst pixel of every configuration in a regime) a recommendation accepts.
BUDGET_PX = 0.25
DRIFT_BUDGETS = (0.1, 0.5, 1.0)  # screen pixels


def _f(x, digits: int = 3) -> str:
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return "–"
    if isinstance(x, float) and (x == 0 or 1e-3 <= abs(x) < 1e5):
        return f"{x:.{digits}g}"
    if isinstance(x, float):
        return f"{x:.{max(digits - 1, 1)}e}"
    return str(x)


def first_row(rows, **match):
    for r in rows:
        if all(r.get(k) == v for k, v in match.items()):
            return r
    return None


def select_rows(rows, **match):
    return [r for r in rows if all(r.get(k) == v for k, v in match.items())]


def single_precision(name: str) -> str:
    return "float32" if name == "hardware" else METHODS[name].precisions[0]


def _err(rows, sweep, method, key="max_err_px", **match):
    r = first_row(rows, sweep=sweep, method=method, precision=single_precision(method), **match)
    return r[key] if r and r[key] is not None else float("nan")


def _finite(x) -> bool:
    return isinstance(x, float) and math.isfinite(x)


def power_fit(lengths, errors) -> tuple[float, float, float]:
    """Least-squares fit error ~ c L^p in log-log: (p, log c, the largest factor a point lies off the fit)."""
    pairs = [(math.log(n), math.log(e)) for n, e in zip(lengths, errors) if e > 0 and math.isfinite(e)]
    if len(pairs) < 2:
        return float("nan"), float("nan"), float("nan")
    x, y = np.array(pairs).T
    slope, offset = np.polyfit(x, y, 1)
    return float(slope), float(offset), float(np.exp(np.abs(y - (slope * x + offset)).max()))


def fitted_length(slope: float, offset: float, budget: float) -> float:
    """The span length where the fitted error reaches ``budget``."""
    return math.exp((math.log(budget) - offset) / slope) if slope > 0 else float("nan")


def speed_frames(rows) -> list[tuple[int, int]]:
    return list(dict.fromkeys((r["span_length"], r["spans"]) for r in select_rows(rows, sweep="speed")))


def speed_row(rows, method: str, frame: tuple[int, int] | None = None):
    frames = speed_frames(rows)
    if not frames:
        return None
    w, h = frame or frames[0]
    return first_row(rows, sweep="speed", method=method, span_length=w, spans=h)


def _named(r, key: str, unit: str = "×") -> str:
    return f"`{r['method']}` {_f(r[key])}{unit}"
