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

The second tally, ``fused``, counts the same code as hardware with fused multiply-add executes it: a product whose
only use is an addition of the same shape becomes one ``fma`` with it (the product is known by identity: it is
the array ``mul`` returned, handed straight to ``add``). Guards are left out of it (on such hardware
``fma(t, 1, c)`` is the addition it replaces). The arithmetic itself is never fused: every result is rounded as
the unfused code rounds it; ``fused`` only says how many instructions the same order needs there.
"""

from __future__ import annotations

import weakref
from collections import Counter

import numpy as np


class Arith:
    """Elementwise arithmetic in ``dtype`` (float32 or float64), tallying operations per kind."""

    def __init__(self, dtype):
        self.dtype = np.dtype(dtype)
        if self.dtype not in (np.float32, np.float64):
            raise ValueError(f"Arith: dtype {self.dtype}: expected float32 or float64")
        self.tally: Counter = Counter()
        self.fused: Counter = Counter()  # the same operations with each product fused into the add that uses it
        self._products = weakref.WeakValueDictionary()  # id -> a product no operation has used yet
        self._fused = weakref.WeakValueDictionary()  # id -> a product fused into the one addition that used it

    def cast(self, x) -> np.ndarray:
        """``x`` rounded to this precision (a conversion, not counted)."""
        return np.asarray(x, dtype=self.dtype)

    def _count(self, kind: str, result: np.ndarray) -> np.ndarray:
        self.tally[kind] += result.size
        return result

    def _use(self, *operands) -> None:
        """Operands are used: a product already fused into an addition is used twice, so it is a multiplication
        after all and that addition a plain one; a product no addition has taken yet can no longer be fused."""
        for x in operands:
            fused = self._fused.get(id(x))
            if fused is x:
                del self._fused[id(x)]
                self.fused["fma"] -= x.size
                self.fused["mul"] += x.size
                self.fused["add"] += x.size
            if self._products.get(id(x)) is x:
                del self._products[id(x)]

    def _count_add(self, result: np.ndarray, *operands) -> np.ndarray:
        """An addition: one ``add`` each, or, in ``fused``, an ``fma`` with a product of its shape no other operation
        has used."""
        self._count("add", result)
        for x in operands:
            if self._products.get(id(x)) is x and x.size == result.size:
                del self._products[id(x)]
                self._use(*(y for y in operands if y is not x))
                self._fused[id(x)] = x
                self.fused["mul"] -= x.size
                self.fused["fma"] += result.size
                return result
        self._use(*operands)
        self.fused["add"] += result.size
        return result

    def add(self, a, b) -> np.ndarray:
        return self._count_add(np.add(a, b, dtype=self.dtype), a, b)

    def sub(self, a, b) -> np.ndarray:
        return self._count_add(np.subtract(a, b, dtype=self.dtype), a, b)

    def mul(self, a, b) -> np.ndarray:
        self._use(a, b)
        result = self._count("mul", np.multiply(a, b, dtype=self.dtype))
        self.fused["mul"] += result.size
        if isinstance(result, np.ndarray):  # a per-polygon scalar product is not worth fusing (nor weakly referable)
            self._products[id(result)] = result
        return result

    def div(self, a, b) -> np.ndarray:
        self._use(a, b)
        with np.errstate(divide="ignore", invalid="ignore"):  # x / 0 only where the result is flagged
            result = self._count("div", np.divide(a, b, dtype=self.dtype))
        self.fused["div"] += result.size
        return result

    def sqrt(self, a) -> np.ndarray:
        self._use(a)
        with np.errstate(invalid="ignore"):  # the square root of a negative only where the result is not used
            result = self._count("sqrt", np.sqrt(self.cast(a)))
        self.fused["sqrt"] += result.size
        return result

    def guard(self, a) -> np.ndarray:
        """``a`` times the kernels' opaque 1.0 (exact)."""
        self._use(a)
        return self._count("guard", np.multiply(a, self.dtype.type(1), dtype=self.dtype))

    def running_sum(self, a, axis: int = -1) -> np.ndarray:
        """Left-to-right running sums along ``axis``: out[0] = a[0], out[i] = out[i-1] + a[i]."""
        a = self.cast(a)
        out = np.add.accumulate(a, axis=axis, dtype=self.dtype)
        adds = a.size - a.size // max(a.shape[axis], 1)
        self.tally["add"] += adds
        self.fused["add"] += adds
        return out

    def int_running_sum(self, a, axis: int = -1) -> np.ndarray:
        """Left-to-right int32 running sums (wrapping, as WGSL's i32 addition)."""
        a = np.asarray(a, np.int32)
        out = np.add.accumulate(a, axis=axis, dtype=np.int32)
        adds = a.size - a.size // max(a.shape[axis], 1)
        self.tally["int_add"] += adds
        self.fused["int_add"] += adds
        return out
