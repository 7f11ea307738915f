"""Arithmetic that rounds every operation in one precision and counts what it does.

numpy rounds each float32 operation on float32 arrays to float32 (IEEE round to nearest even), so a computation
written with these calls, in the order a kernel does it, is an exact float32 emulation of that kernel. Running
sums use ``np.add.accumulate``: it adds left to right (``w_n = w_{n-1} + a_n``), exactly the incremental formula;
``np.sum`` would add pairwise, which is a different (more accurate) algorithm.

The tally counts element operations by kind (``add`` includes subtractions, as operation counts usually do), so
the operation counts per texel the report states come from running the code, not from reading it. ``guard`` is
a multiplication by 1.0 that a shader compiler cannot see through (the kernels take it from a uniform): it fixes
the evaluation order the kernels' compiler would otherwise change (lavapipe reassociates ``a x + b y + c`` and
cancels Kahan's ``(t - s) - y`` to 0); here it changes nothing and is counted apart from the arithmetic.
"""

from __future__ import annotations

from collections import Counter

import numpy as np


class Arith:
    """Elementwise arithmetic in ``dtype`` (float32 or float64), tallying operations per kind."""

    def __init__(self, dtype):
        self.dtype = np.dtype(dtype)
        if self.dtype not in (np.float32, np.float64):
            raise ValueError(f"Arith: dtype {self.dtype}: expected float32 or float64")
        self.tally: Counter = Counter()

    def cast(self, x) -> np.ndarray:
        """``x`` rounded to this precision (a conversion, not counted)."""
        return np.asarray(x, dtype=self.dtype)

    def _count(self, kind: str, result: np.ndarray) -> np.ndarray:
        self.tally[kind] += result.size
        return result

    def add(self, a, b) -> np.ndarray:
        return self._count("add", np.add(a, b, dtype=self.dtype))

    def sub(self, a, b) -> np.ndarray:
        return self._count("add", np.subtract(a, b, dtype=self.dtype))

    def mul(self, a, b) -> np.ndarray:
        return self._count("mul", np.multiply(a, b, dtype=self.dtype))

    def div(self, a, b) -> np.ndarray:
        with np.errstate(divide="ignore", invalid="ignore"):  # x / 0 only where the result is flagged
            return self._count("div", np.divide(a, b, dtype=self.dtype))

    def guard(self, a) -> np.ndarray:
        """``a`` times the kernels' opaque 1.0 (exact)."""
        return self._count("guard", np.multiply(a, self.dtype.type(1), dtype=self.dtype))

    def running_sum(self, a, axis: int = -1) -> np.ndarray:
        """Left-to-right running sums along ``axis``: out[0] = a[0], out[i] = out[i-1] + a[i]."""
        a = self.cast(a)
        out = np.add.accumulate(a, axis=axis, dtype=self.dtype)
        self.tally["add"] += a.size - a.size // max(a.shape[axis], 1)
        return out

    def int_running_sum(self, a, axis: int = -1) -> np.ndarray:
        """Left-to-right int32 running sums (wrapping, as WGSL's i32 addition)."""
        a = np.asarray(a, np.int32)
        out = np.add.accumulate(a, axis=axis, dtype=np.int32)
        self.tally["int_add"] += a.size - a.size // max(a.shape[axis], 1)
        return out
