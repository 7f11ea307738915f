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

Every loop has the same arguments (``Arguments``): the coefficients in the loop's precision, what the
double-single and fixed-point forms add (the increment's low part, the fixed-point start values, steps and
scales), the spans (x0, y, the span setup's clip [first, end)), the method's parameter, and the outputs.
"""

from __future__ import annotations

import contextlib
import re
import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from wgpuviewer.core.errors import UserError

from .geometry import UMAX, Spans, defined_range
from .methods import METHODS, PRECISION_DTYPE, Result, fixed_setup, split

#: The most lanes the parallel form keeps (methods.PARALLEL_THREADS).
MAX_LANES = 32
BUILDS = ("scalar", "simd")


def numba_module():
    """numba, or a UserError saying how to install it."""
    try:
        import numba
    except ImportError:
        raise UserError("the perspective study's compiled loops need numba: pip install 'wgpuviewer[bench]'") from None
    return numba


def loop_sources(ftype) -> dict[str, Callable]:
    """Every loop as a Python function in the float type ``ftype`` (np.float32 or np.float64), for numba; the
    per-pixel helpers they call are compiled with the first loop that calls them, so each build gets its own."""
    numba = numba_module()
    jit = numba.njit(fastmath=False, error_model="numpy", nogil=True)
    zero, one, two, umax = ftype(0), ftype(1), ftype(2), ftype(UMAX)

    @jit
    def put(ru, rv, rf, n, wu, wv, q, inside):
        """Pixel n from (w_u, w_v, q): the divisions, or 0 and a flag (methods._divide)."""
        ok = (q > zero) & (abs(wu) <= umax * q) & (abs(wv) <= umax * q) & inside
        u = wu / q
        v = wv / q
        ru[n] = u if ok else zero
        rv[n] = v if ok else zero
        rf[n] = not ok

    @jit
    def put_rcp(ru, rv, rf, n, wu, wv, q, inside):
        """Pixel n with one division (methods._reciprocal)."""
        ok = (q > zero) & (abs(wu) <= umax * q) & (abs(wv) <= umax * q) & inside
        r = one / q
        u = wu * r
        v = wv * r
        ru[n] = u if ok else zero
        rv[n] = v if ok else zero
        rf[n] = not ok

    @jit
    def exact(su, sv, sq, au, av, aq, p, inside):
        """u, v and flag at span position p by the span form (0 where flagged): an anchor of the subdivisions."""
        pf = ftype(p)
        wu = su + au * pf
        wv = sv + av * pf
        q = sq + aq * pf
        ok = (q > zero) & (abs(wu) <= umax * q) & (abs(wv) <= umax * q) & inside
        u = wu / q
        v = wv / q
        return (u if ok else zero), (v if ok else zero), not ok, q

    @jit
    def line(ru, rv, rf, a, b, cu, cv, cf, du, dv, df):
        """Pixels a .. b - 1 linear from anchor a (cu, cv, cf) towards anchor b (du, dv, df) (methods._interpolate)."""
        width = ftype(b - a)
        slope_u = (du - cu) / width
        slope_v = (dv - cv) / width
        flagged = cf | df
        for m in range(b - a):
            mf = ftype(m)
            lu = cu + mf * slope_u
            lv = cv + mf * slope_v
            ru[a + m] = zero if flagged else lu
            rv[a + m] = zero if flagged else lv
            rf[a + m] = flagged

    @jit
    def start(k, x0, y):
        """The per-span constants a x0 + b y + c (methods.span_start)."""
        xf, yf = ftype(x0), ftype(y)
        return ((k[0, 0] * xf + k[0, 1] * yf) + k[0, 2], (k[1, 0] * xf + k[1, 1] * yf) + k[1, 2],
                (k[2, 0] * xf + k[2, 1] * yf) + k[2, 2])

    def direct_like(store):
        def loop(k, a_lo, ratio, fx_step, fx_start, x0, y, first, end, param, out_u, out_v, out_f):
            au, bu, cu = k[0, 0], k[0, 1], k[0, 2]
            av, bv, cv = k[1, 0], k[1, 1], k[1, 2]
            aq, bq, cq = k[2, 0], k[2, 1], k[2, 2]
            length = out_u.shape[1]
            for s in range(x0.size):
                ru, rv, rf = out_u[s], out_v[s], out_f[s]
                yf, xs, lo, hi = ftype(y[s]), x0[s], first[s], end[s]
                for n in range(length):
                    x = ftype(xs + n)
                    store(ru, rv, rf, n, (au * x + bu * yf) + cu, (av * x + bv * yf) + cv, (aq * x + bq * yf) + cq,
                          (n >= lo) & (n < hi))
        return loop

    def span_like(store):
        def loop(k, a_lo, ratio, fx_step, fx_start, x0, y, first, end, param, out_u, out_v, out_f):
            au, av, aq = k[0, 0], k[1, 0], k[2, 0]
            length = out_u.shape[1]
            for s in range(x0.size):
                ru, rv, rf = out_u[s], out_v[s], out_f[s]
                su, sv, sq = start(k, x0[s], y[s])
                lo, hi = first[s], end[s]
                for n in range(length):
                    nf = ftype(n)
                    store(ru, rv, rf, n, su + au * nf, sv + av * nf, sq + aq * nf, (n >= lo) & (n < hi))
        return loop

    def incremental(k, a_lo, ratio, fx_step, fx_start, x0, y, first, end, param, out_u, out_v, out_f):
        au, av, aq = k[0, 0], k[1, 0], k[2, 0]
        length = out_u.shape[1]
        for s in range(x0.size):
            ru, rv, rf = out_u[s], out_v[s], out_f[s]
            wu, wv, q = start(k, x0[s], y[s])
            lo, hi = first[s], end[s]
            for n in range(length):
                put(ru, rv, rf, n, wu, wv, q, (n >= lo) & (n < hi))
                wu = wu + au
                wv = wv + av
                q = q + aq

    def parallel(k, a_lo, ratio, fx_step, fx_start, x0, y, first, end, param, out_u, out_v, out_f):
        au, av, aq = k[0, 0], k[1, 0], k[2, 0]
        lanes = min(max(param, 1), MAX_LANES)
        stride_u, stride_v, stride_q = au * ftype(lanes), av * ftype(lanes), aq * ftype(lanes)
        lane_u, lane_v, lane_q = np.empty(MAX_LANES, ftype), np.empty(MAX_LANES, ftype), np.empty(MAX_LANES, ftype)
        length = out_u.shape[1]
        for s in range(x0.size):
            ru, rv, rf = out_u[s], out_v[s], out_f[s]
            wu, wv, q = start(k, x0[s], y[s])
            lo, hi = first[s], end[s]
            for j in range(lanes):  # lane j starts at w_j, by j steps of formula (4)
                lane_u[j], lane_v[j], lane_q[j] = wu, wv, q
                wu = wu + au
                wv = wv + av
                q = q + aq
            for base in range(0, length, lanes):
                for j in range(min(lanes, length - base)):
                    n = base + j
                    put(ru, rv, rf, n, lane_u[j], lane_v[j], lane_q[j], (n >= lo) & (n < hi))
                    lane_u[j] = lane_u[j] + stride_u
                    lane_v[j] = lane_v[j] + stride_v
                    lane_q[j] = lane_q[j] + stride_q

    def two_ended(k, a_lo, ratio, fx_step, fx_start, x0, y, first, end, param, out_u, out_v, out_f):
        au, av, aq = k[0, 0], k[1, 0], k[2, 0]
        length = out_u.shape[1]
        half = (length + 1) // 2
        last = ftype(length - 1)
        for s in range(x0.size):
            ru, rv, rf = out_u[s], out_v[s], out_f[s]
            su, sv, sq = start(k, x0[s], y[s])
            lo, hi = first[s], end[s]
            wu, wv, q = su, sv, sq
            for n in range(half):
                put(ru, rv, rf, n, wu, wv, q, (n >= lo) & (n < hi))
                wu = wu + au
                wv = wv + av
                q = q + aq
            wu, wv, q = su + au * last, sv + av * last, sq + aq * last
            for i in range(length - half):  # w + (-a) is w - a exactly
                n = length - 1 - i
                put(ru, rv, rf, n, wu, wv, q, (n >= lo) & (n < hi))
                wu = wu + -au
                wv = wv + -av
                q = q + -aq

    def subdivided(k, a_lo, ratio, fx_step, fx_start, x0, y, first, end, param, out_u, out_v, out_f):
        au, av, aq = k[0, 0], k[1, 0], k[2, 0]
        every = max(param, 1)
        length = out_u.shape[1]
        for s in range(x0.size):
            ru, rv, rf = out_u[s], out_v[s], out_f[s]
            su, sv, sq = start(k, x0[s], y[s])
            lo, hi = first[s], end[s]
            cu, cv, cf, _ = exact(su, sv, sq, au, av, aq, 0, (lo <= 0) & (hi > 0))
            a = 0
            while a < length - 1:
                b = min(a + every, length - 1)
                du, dv, df, _ = exact(su, sv, sq, au, av, aq, b, (b >= lo) & (b < hi))
                line(ru, rv, rf, a, b, cu, cv, cf, du, dv, df)
                a, cu, cv, cf = b, du, dv, df
            ru[length - 1] = cu
            rv[length - 1] = cv
            rf[length - 1] = cf

    def adaptive(k, a_lo, ratio, fx_step, fx_start, x0, y, first, end, param, out_u, out_v, out_f):
        au, av, aq = k[0, 0], k[1, 0], k[2, 0]
        # methods.segment_rule
        ad = abs(aq)
        m = -aq if aq < zero else zero
        e = ftype(param)
        m2, de, scale = m * m, ad * e, two / (e * ad)
        length = out_u.shape[1]
        for s in range(x0.size):
            ru, rv, rf = out_u[s], out_v[s], out_f[s]
            su, sv, sq = start(k, x0[s], y[s])
            lo, hi = first[s], end[s]
            cu, cv, cf, q = exact(su, sv, sq, au, av, aq, 0, (lo <= 0) & (hi > 0))
            a = 0
            while a < length - 1:
                remaining = length - 1 - a
                step = 1  # methods.segment_length
                if ad == zero:
                    step = remaining
                elif q > zero:
                    sl = (np.sqrt(m2 + de * q) - m) * scale
                    if sl >= one:
                        step = int(np.floor(min(sl, ftype(remaining))))
                b = a + step
                du, dv, df, q = exact(su, sv, sq, au, av, aq, b, (b >= lo) & (b < hi))
                line(ru, rv, rf, a, b, cu, cv, cf, du, dv, df)
                a, cu, cv, cf = b, du, dv, df
            ru[length - 1] = cu
            rv[length - 1] = cv
            rf[length - 1] = cf

    def reanchor(k, a_lo, ratio, fx_step, fx_start, x0, y, first, end, param, out_u, out_v, out_f):
        au, av, aq = k[0, 0], k[1, 0], k[2, 0]
        every = max(param, 1)
        length = out_u.shape[1]
        for s in range(x0.size):
            ru, rv, rf = out_u[s], out_v[s], out_f[s]
            su, sv, sq = start(k, x0[s], y[s])
            lo, hi = first[s], end[s]
            wu, wv, q = su, sv, sq
            for n in range(length):
                if n % every == 0:
                    nf = ftype(n)
                    wu, wv, q = su + au * nf, sv + av * nf, sq + aq * nf
                put(ru, rv, rf, n, wu, wv, q, (n >= lo) & (n < hi))
                wu = wu + au
                wv = wv + av
                q = q + aq

    def kahan(k, a_lo, ratio, fx_step, fx_start, x0, y, first, end, param, out_u, out_v, out_f):
        au, av, aq = k[0, 0], k[1, 0], k[2, 0]
        length = out_u.shape[1]
        for s in range(x0.size):
            ru, rv, rf = out_u[s], out_v[s], out_f[s]
            wu, wv, q = start(k, x0[s], y[s])
            cu = cv = cq = zero
            lo, hi = first[s], end[s]
            for n in range(length):
                put(ru, rv, rf, n, wu, wv, q, (n >= lo) & (n < hi))
                yu, yv, yq = au - cu, av - cv, aq - cq
                tu, tv, tq = wu + yu, wv + yv, q + yq
                cu, cv, cq = (tu - wu) - yu, (tv - wv) - yv, (tq - q) - yq
                wu, wv, q = tu, tv, tq

    @jit
    def two_float_step(h, lo, a, a_lo):
        """hi + lo plus a + a_lo: TwoSum of h + a, then the low parts (methods.double_single)."""
        sm = h + a
        bb = sm - h
        err = (h - (sm - bb)) + (a - bb)
        e = err + (lo + a_lo)
        h2 = sm + e
        return h2, e - (h2 - sm)

    def double_single(k, a_lo, ratio, fx_step, fx_start, x0, y, first, end, param, out_u, out_v, out_f):
        au, av, aq = k[0, 0], k[1, 0], k[2, 0]
        lu, lv, lq = a_lo[0], a_lo[1], a_lo[2]
        length = out_u.shape[1]
        for s in range(x0.size):
            ru, rv, rf = out_u[s], out_v[s], out_f[s]
            hu, hv, hq = start(k, x0[s], y[s])
            ou = ov = oq = zero
            lo, hi = first[s], end[s]
            for n in range(length):
                put(ru, rv, rf, n, hu + ou, hv + ov, hq + oq, (n >= lo) & (n < hi))
                hu, ou = two_float_step(hu, ou, au, lu)
                hv, ov = two_float_step(hv, ov, av, lv)
                hq, oq = two_float_step(hq, oq, aq, lq)

    def fixed16_16(k, a_lo, ratio, fx_step, fx_start, x0, y, first, end, param, out_u, out_v, out_f):
        su, sv, sq = fx_step[0], fx_step[1], fx_step[2]
        length = out_u.shape[1]
        for s in range(x0.size):
            ru, rv, rf = out_u[s], out_v[s], out_f[s]
            wu, wv, q = fx_start[s, 0], fx_start[s, 1], fx_start[s, 2]
            lo, hi = first[s], end[s]
            for n in range(length):
                fu, fv, fq = ftype(wu), ftype(wv), ftype(q)
                u = (fu / fq) * ratio[0]
                v = (fv / fq) * ratio[1]
                ok = (fq > zero) & (abs(u) <= umax) & (abs(v) <= umax) & (n >= lo) & (n < hi)
                ru[n] = u if ok else zero
                rv[n] = v if ok else zero
                rf[n] = not ok
                wu = np.int32(wu + su)  # int32 wraps, as the numpy twin's and WGSL's i32 sums
                wv = np.int32(wv + sv)
                q = np.int32(q + sq)

    return {"direct": direct_like(put), "direct_rcp": direct_like(put_rcp), "span": span_like(put),
            "span_rcp": span_like(put_rcp), "incremental": incremental, "parallel": parallel, "two_ended": two_ended,
            "subdivided": subdivided, "adaptive": adaptive, "reanchor": reanchor, "kahan": kahan,
            "double_single": double_single, "fixed16_16": fixed16_16}


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
            if dtype not in self._sources:
                self._sources[dtype] = loop_sources(dtype)
            dispatcher = numba.njit(fastmath=False, error_model="numpy", nogil=True)(self._sources[dtype][kernel])
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
