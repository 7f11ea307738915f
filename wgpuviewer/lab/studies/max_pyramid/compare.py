"""Equal error and equal cost between the pyramid walk and a linear search's sweep: each sweep (one technique, its
layer count doubling) is a cost-error curve; the cost it needs to reach an error target, and the error it has at a
given cost, are interpolated on that curve in log-log (between the two settings around the crossing), not read at
the next grid point. Beyond the sweep a value is a bound, flagged:

- ``<=``: already the cheapest setting meets the target (the cost is at most this);
- ``>``: no setting meets it (the cost is more than the dearest setting's);
- at a cost below the cheapest setting the error is ``>=`` that setting's, above the dearest ``<=`` its error.

``best_linear`` and ``ratio`` read a results row: the cheapest linear search at a target, the walk's cost over it.
"""

from __future__ import annotations

import math

from .tables import COMPETITORS

#: Errors below this (texels) count as this in the log-log interpolation (an exact hit has error ~1e-5).
ERROR_FLOOR = 1e-6


def _log(x: float, floor: float = ERROR_FLOOR) -> float:
    return math.log(max(x, floor))


def cost_at_error(curve: list[tuple[float, float]], target: float) -> tuple[float, str]:
    """(cost, flag) where ``curve`` [(cost, error)] in sweep order first reaches error <= ``target``."""
    for i, (cost, error) in enumerate(curve):
        if error <= target:
            if i == 0:
                return cost, "<="
            c0, e0 = curve[i - 1]
            f = (_log(target) - _log(e0)) / (_log(error) - _log(e0))
            return math.exp(_log(c0) + f * (_log(cost) - _log(c0))), ""
    return curve[-1][0], ">"


def error_at_cost(curve: list[tuple[float, float]], cost: float) -> tuple[float, str]:
    """(error, flag) of ``curve`` [(cost, error)] at ``cost`` (the curve sorted by cost first)."""
    points = sorted(curve)
    if cost <= points[0][0]:
        return points[0][1], ">=" if cost < points[0][0] else ""
    for (c0, e0), (c1, e1) in zip(points, points[1:]):
        if c0 <= cost <= c1:
            f = 0.0 if c1 == c0 else (_log(cost) - _log(c0)) / (_log(c1) - _log(c0))
            return math.exp(_log(e0) + f * (_log(e1) - _log(e0))), ""
    return points[-1][1], "<="


def best_linear(row: dict, criterion: str) -> tuple[float, str, str]:
    """(SIMD-tile cost, flag, technique) of the cheapest linear search at the criterion's target for ``row``."""
    return min((row[f"{c}_simd_{criterion}"], row[f"{c}_flag_{criterion}"], c) for c in COMPETITORS)


def ratio(row: dict, criterion: str) -> tuple[float, str]:
    """The walk's SIMD-tile fetches over the best linear search's at the target (< 1: the walk is cheaper), and the
    bound it is: '<' where no linear setting met the target (the true ratio is smaller), '>=' where the cheapest
    setting already met it (the true ratio may be larger)."""
    cost, flag, _ = best_linear(row, criterion)
    return row["fetches_simd"] / cost, {">": "<", "<=": ">=", "": ""}[flag]
