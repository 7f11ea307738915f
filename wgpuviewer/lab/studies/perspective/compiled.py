"""The methods as compiled scalar loops (numba): the platform the paper's operation counts are about, a scanline
inner loop, one span at a time and one pixel at a time, timed per texel.

Each loop (``LOOPS``, by ``Method.kernel``) is the twin of its numpy form (``methods``) and of its WGSL kernel: the
same operations in the same order, in the method's precision, with IEEE semantics (numba without fast-math: no
reassociation, no contraction into fused multiply-adds; the ``numpy`` error model: x / 0 is inf, not an
exception), so it writes the numpy form's uv and flags bit for bit (a test pins it, float32 and float64). The
compiler guards of the WGSL kernels (``arith.Arith.guard``) are not needed here: LLVM keeps the written order.

Two builds of every loop:

- ``scalar``: compiled with LLVM's loop and SLP vectorisers off: one pixel at a time, as the paper's scanline loop;
- ``simd``: the same code with the vectorisers on (numba's default). A loop without a loop-carried dependency (the
  per-pixel forms, the linear segments of the subdivided ones) can then run several pixels per instruction; the
  running sums cannot (a float recurrence is not reassociated). ``vectorisation`` reads the optimised LLVM IR to
  say which loops were vectorised and how wide.

The loops' source is ``loops`` (``loops.loop_sources``). Every loop has the same arguments (``Arguments``): the
coefficients in the loop's precision, what the double-single and fixed-point forms add (the increment's low part,
the fixed-point start values, steps and scales), the spans (x0, y, the span setup's clip [first, end)), the method's
parameter, and the outputs.
"""

from __future__ import annotations

import contextlib
import re
import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from wgpuviewer.core.errors import UserError

from .geometry import Spans, defined_range
from .loops import loop_sources
from .methods import METHODS, PRECISION_DTYPE, Result, fixed_setup, split

BUILDS = ("scalar", "simd")


def numba_module():
    """numba, or a UserError saying how to install it."""
    try:
        import numba
    except ImportError:
        raise UserError("the perspective study's compiled loops need numba: pip install 'wgpuviewer[bench]'") from None
    return numba


#: The loops, by ``Method.kernel``.
LOOPS = ("direct", "direct_rcp", "span", "span_rcp", "incremental", "parallel", "two_ended", "subdivided", "adaptive",
         "reanchor", "kahan", "double_single", "fixed16_16")


@contextlib.contextmanager
def _vectorisers(on: bool):
    """LLVM's loop and SLP vectorisers on or off for what numba compiles inside (it reads them per compilation)."""
    from numba.core import config

    saved = config.LOOP_VECTORIZE, config.SLP_VECTORIZE
    config.LOOP_VECTORIZE = config.SLP_VECTORIZE = on
    try:
        yield
    finally:
        config.LOOP_VECTORIZE, config.SLP_VECTORIZE = saved


@dataclass
class Arguments:
    """A loop's inputs for one method on some spans, and outputs to write into."""

    k: np.ndarray  # (3, 3) in the loop's precision
    a_lo: np.ndarray  # (3,) double_single: the float64 x coefficients minus their float32 parts
    ratio: np.ndarray  # (2,) fixed16_16: the scales' ratios
    fx_step: np.ndarray  # (3,) int32
    fx_start: np.ndarray  # (R, 3) int32
    x0: np.ndarray  # (R,) int64
    y: np.ndarray
    first: np.ndarray  # the span setup's clip (geometry.defined_range)
    end: np.ndarray
    param: int
    u: np.ndarray  # (R, L) outputs
    v: np.ndarray
    flagged: np.ndarray

    def tuple(self) -> tuple:
        return (self.k, self.a_lo, self.ratio, self.fx_step, self.fx_start, self.x0, self.y, self.first, self.end,
                self.param, self.u, self.v, self.flagged)


def arguments(name: str, coefficients: np.ndarray, spans: Spans, outputs: Result | None = None) -> Arguments:
    """Method ``name``'s loop arguments on ``spans`` in its first precision (into ``outputs``, or new arrays)."""
    return _arguments(name, METHODS[name].precisions[0], coefficients, spans, outputs)


def _arguments(name: str, precision: str, coefficients, spans: Spans, outputs: Result | None) -> Arguments:
    method = METHODS[name]
    dtype = PRECISION_DTYPE[precision]
    k64 = np.asarray(coefficients, np.float64)
    fx_step, fx_start, ratio = np.zeros(3, np.int32), np.zeros((spans.count, 3), np.int32), np.zeros(2, dtype)
    if method.kernel == "fixed16_16":
        fx = fixed_setup(k64, spans)
        fx_step, fx_start, ratio = fx.steps, np.ascontiguousarray(fx.starts.T), fx.ratio.astype(dtype)
    first, end = defined_range(k64, spans)
    shape = (spans.count, spans.length)
    if outputs is None or outputs.u.dtype != dtype or outputs.u.shape != shape:
        outputs = Result(np.empty(shape, dtype), np.empty(shape, dtype), np.empty(shape, bool))
    return Arguments(np.ascontiguousarray(k64.astype(dtype)), split(k64)[1][:, 0].astype(dtype), ratio, fx_step,
                     fx_start, spans.x0.astype(np.int64), spans.y.astype(np.int64), first.astype(np.int64),
                     end.astype(np.int64), int(method.param), outputs.u, outputs.v, outputs.flagged)


class Build:
    """One build (``BUILDS``) of every loop, each compiled when first asked for (``compile`` ahead of timing)."""

    def __init__(self, name: str):
        if name not in BUILDS:
            raise ValueError(f"build {name!r}: expected one of {', '.join(BUILDS)}")
        self.name = name
        self._sources: dict[type, dict[str, Callable]] = {}  # per float type: this build's loops and helpers
        self._loops: dict[tuple[str, type], object] = {}

    def loop(self, kernel: str, dtype) -> object:
        """The compiled loop ``kernel`` in ``dtype`` (a numba dispatcher with one signature, no other compiled)."""
        numba = numba_module()
        dtype = np.dtype(dtype).type
        key = (kernel, dtype)
        if key not in self._loops:
            jit = numba.njit(fastmath=False, error_model="numpy", nogil=True)
            if dtype not in self._sources:
                self._sources[dtype] = loop_sources(jit, dtype)
            dispatcher = jit(self._sources[dtype][kernel])
            f, i32, i64 = numba.from_dtype(np.dtype(dtype)), numba.int32, numba.int64
            arr = numba.types.Array
            signature = (arr(f, 2, "C"), arr(f, 1, "C"), arr(f, 1, "C"), arr(i32, 1, "C"), arr(i32, 2, "C"),
                         *(arr(i64, 1, "C"),) * 4, i64, arr(f, 2, "C"), arr(f, 2, "C"), arr(numba.boolean, 2, "C"))
            with _vectorisers(self.name == "simd"):
                dispatcher.compile(signature)
            dispatcher.disable_compile()  # a call with other types is an error, not a compilation outside the build
            self._loops[key] = dispatcher
        return self._loops[key]

    def compile(self, names, precisions: bool = False) -> None:
        """Compile the loops of methods ``names`` now (in their first precision, or ``precisions``: all of them)."""
        for name in names:
            method = METHODS[name]
            for precision in method.precisions if precisions else method.precisions[:1]:
                self.loop(method.kernel, PRECISION_DTYPE[precision])

    def evaluate(self, name: str, precision: str, coefficients, spans: Spans) -> Result:
        """Method ``name`` in ``precision`` on ``spans``: methods.evaluate's result, by the compiled loop."""
        method = METHODS[name]
        if precision not in method.precisions:
            raise ValueError(f"method {name}: precision {precision!r}; expected one of {', '.join(method.precisions)}")
        args = _arguments(name, precision, coefficients, spans, None)
        self.loop(method.kernel, PRECISION_DTYPE[precision])(*args.tuple())
        return Result(args.u, args.v, args.flagged)

    def vectorisation(self, name: str) -> str:
        """What LLVM made of method ``name``'s float32 loop, read from the optimised IR: ``loop xN`` (the loop
        vectoriser ran N lanes), ``slp xN`` (only straight-line code packed N wide), or ``scalar``."""
        method = METHODS[name]
        ir = self.loop(method.kernel, PRECISION_DTYPE[method.precisions[0]]).inspect_llvm()
        ir = next(iter(ir.values())) if isinstance(ir, dict) else ir
        widths = [int(w) for w in re.findall(r"= f(?:add|sub|mul|div) (?:fast )?<(\d+) x float>", ir)]
        if not widths:
            return "scalar"
        return f"{'loop' if 'llvm.loop.isvectorized' in ir else 'slp'} x{max(widths)}"


_BUILDS: dict[str, Build] = {}


def build(name: str) -> Build:
    """The process's build ``name`` (its loops compiled once per process, shared by every run and test)."""
    if name not in _BUILDS:
        _BUILDS[name] = Build(name)
    return _BUILDS[name]


@dataclass
class Timing:
    """Per-texel times of one build's loops over repeats (round robin), and their ratios to ``direct``'s."""

    ns: dict[str, np.ndarray]  # method -> (repeats,) ns per texel
    calls: dict[str, int]  # calls per sample

    def median(self, name: str) -> float:
        return float(np.median(self.ns[name]))

    def ratio(self, name: str, base: str = "direct") -> float:
        """The median over repeats of the time over ``base``'s in the same repeat."""
        return float(np.median(self.ns[name] / self.ns[base]))

    def spread(self, name: str) -> float:
        """Interquartile range of the repeats over their median."""
        q75, q25 = np.percentile(self.ns[name], [75, 25])
        return float((q75 - q25) / np.median(self.ns[name]))


def time_loops(build: Build, names, coefficients, spans: Spans, repeats: int, sample_seconds: float) -> Timing:
    """Time methods ``names`` (float32 or their first precision) on ``spans``: a warm-up call each, then
    ``repeats`` rounds in which every method, in an order rotating by one each round, runs enough calls back to back
    to last ``sample_seconds``; one sample is that run's wall time per texel. All write into the same outputs."""
    names = list(names)
    outputs = Result(*(np.empty((spans.count, spans.length), t) for t in (np.float32, np.float32, bool)))
    calls = {}
    for name in names:
        args = arguments(name, coefficients, spans, outputs).tuple()
        loop = build.loop(METHODS[name].kernel, args[0].dtype)
        calls[name] = (loop, args)
    texels = spans.count * spans.length
    count = {}
    for name, (loop, args) in calls.items():
        loop(*args)  # warm-up (caches, page faults)
        t = time.perf_counter()
        loop(*args)
        count[name] = max(1, int(np.ceil(sample_seconds / max(time.perf_counter() - t, 1e-9))))
    samples = {name: [] for name in names}
    for r in range(repeats):
        for name in names[r % len(names):] + names[:r % len(names)]:
            loop, args = calls[name]
            t = time.perf_counter()
            for _ in range(count[name]):
                loop(*args)
            samples[name].append((time.perf_counter() - t) / count[name] / texels * 1e9)
    return Timing({n: np.array(s) for n, s in samples.items()}, count)


def cpu_model() -> str:
    """The CPU's model name (/proc/cpuinfo on Linux; else platform.processor)."""
    import platform

    try:
        with open("/proc/cpuinfo", encoding="utf-8") as f:
            for line in f:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine() or "unknown"
