"""Every way of evaluating the perspective map along a span, as numpy code that rounds each operation in the
method's precision (``arith.Arith``): the exact CPU twin of each WGSL kernel (``wgsl/studies/perspective/``; a test
pins the two bit for bit) and the source of the operation counts.

With K = [[A1, B1, C1], [A2, B2, C2], [D, E, F]] (``geometry``) and span i covering pixels (x0 + n, y), the three
linear forms are w_u = A1 x + B1 y + C1, w_v = A2 x + B2 y + C2, q = D x + E y + F, and u = w_u / q, v = w_v / q.
The methods differ only in how they get w_u, w_v and q at each n (the paper's names; its formulas (1)-(5)):

- ``direct`` (1): all three per pixel from x and y;
- ``span`` (3): per-span constants ut = A x0 + B y + C, then ut + A n per pixel;
- ``incremental`` (4): w_n = w_{n-1} + A (one thread walks the span);
- ``parallel_k`` (5): k threads per span; the first k values by (4), then thread j steps w_{n+k} = w_n + k A;
- ``two_ended``: one thread walks up from n = 0, another down from n = L - 1 (started there by the span form);
- ``subdivided_S``: exact (span form) every S pixels and at the span's end, linear in between (Quake's affine
  subdivision);
- ``adaptive_E``: the same, with each segment as long as the interpolation error bound allows: at most 1/E of a
  pixel (``segment_length``; the bound is derived in docs/perspective.md);

the one-reciprocal forms, which divide once and multiply twice (``r = 1 / q``, ``u = w_u r``, ``v = w_v r``):

- ``direct_rcp``: formula (1) so; ``span_rcp``: formula (3) so;

and the mitigations of the incremental form's drift:

- ``reanchor_M``: incremental, but every M pixels w and q are evaluated afresh by the span form;
- ``kahan``: compensated (Kahan) running sums;
- ``double_single``: a two-float accumulator (hi + lo, about 48 significant bits) stepping by the float64
  increment split into two floats;
- ``fixed16_16``: int32 16.16 fixed-point sums, each quantity scaled by a power of two to at most 2^14, from
  starts rounded from float64 (the stepping error alone), then u = (w_u / q) times the scales' ratio.

Every method flags the pixels the span setup clips away (``geometry.defined_range``: q within its float32
rounding of 0, or |u| or |v| beyond ``UMAX`` / 2) and those whose own values fail ``geometry.valid`` (q <= 0, or
|u| or |v| beyond ``UMAX``), and returns 0 there: output is finite everywhere, and no unflagged pixel lacks a
defined texel.
Sums of three terms and the compensation terms (t - s) - y of the Kahan and two-float sums go through
``Arith.guard`` (times an opaque 1.0): without it the kernels' compiler reorders or cancels them (lavapipe turns
``a x + b y + c`` into ``(a x + c) + b y`` and Kahan's compensation into 0), and the numpy twin would no longer be
the kernel's arithmetic.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from .arith import Arith
from .geometry import UMAX, Spans, inside, valid

FIXED_ONE = 65536  # 16.16: one unit is 2^-16
FIXED_PEAK = 2.0**14  # each fixed-point quantity is scaled to at most this (headroom for the drift)


@dataclass
class Result:
    u: np.ndarray  # (R, L) texels, 0 where flagged
    v: np.ndarray
    flagged: np.ndarray  # (R, L) bool
    exact: int | None = None  # exact (u, v) evaluations (each a division or reciprocal of q): the pixels, or the
    # anchors; None where not counted (the compiled loops, the rasteriser)


def _divide(ar: Arith, w: np.ndarray, clip: np.ndarray) -> Result:
    """u = w_u / q, v = w_v / q from w = (w_u, w_v, q) of shape (3, R, L), with the flags (``clip``: the pixels
    the span setup keeps, geometry.inside)."""
    wu, wv, q = w
    ok = valid(wu, wv, q) & clip
    u, v = ar.div(wu, q), ar.div(wv, q)
    zero = ar.cast(0)
    return Result(np.where(ok, u, zero), np.where(ok, v, zero), ~ok, q.size)


def _reciprocal(ar: Arith, w: np.ndarray, clip: np.ndarray) -> Result:
    """``_divide`` with one division: r = 1 / q, u = w_u r, v = w_v r (each rounded: up to an ulp from w_u / q)."""
    wu, wv, q = w
    ok = valid(wu, wv, q) & clip
    r = ar.div(ar.cast(1), q)
    u, v = ar.mul(wu, r), ar.mul(wv, r)
    zero = ar.cast(0)
    return Result(np.where(ok, u, zero), np.where(ok, v, zero), ~ok, q.size)


def _full(a: np.ndarray, spans: Spans) -> np.ndarray:
    """Per-quantity coefficients (3,) broadcast to (3, R, L) (every pixel does its own operation)."""
    return np.ascontiguousarray(np.broadcast_to(a[:, None, None], (3, spans.count, spans.length)))


def _n(ar: Arith, spans: Spans, values=None) -> np.ndarray:
    """Span positions n (or ``values``) as (R, L) in the method's precision."""
    n = np.arange(spans.length) if values is None else np.asarray(values)
    return ar.cast(np.broadcast_to(n, (spans.count, n.size)))


def span_start(ar: Arith, k: np.ndarray, spans: Spans) -> np.ndarray:
    """The per-span constants (ut_u, ut_v, ub) = A x0 + B y + C, shape (3, R)."""
    x0, y = ar.cast(spans.x0), ar.cast(spans.y)
    return ar.add(ar.guard(ar.add(ar.mul(k[:, 0:1], x0), ar.mul(k[:, 1:2], y))), k[:, 2:3])


def _span_form(ar: Arith, k: np.ndarray, start: np.ndarray, n: np.ndarray) -> np.ndarray:
    """ut + A n for n of shape (R, M): (3, R, M)."""
    a = np.broadcast_to(k[:, 0, None, None], (3, *n.shape))
    return ar.add(start[:, :, None], ar.mul(a, n[None]))


def _steps(first: np.ndarray, step: np.ndarray, count: int) -> np.ndarray:
    """(3, R, count): ``first`` (3, R) then ``step`` (3,) repeated: the operands of a running sum."""
    out = np.empty((*first.shape, count), first.dtype)
    out[..., 0] = first
    out[..., 1:] = step[:, None, None]
    return out


def _direct_form(ar: Arith, k: np.ndarray, spans: Spans) -> np.ndarray:
    """Formula (1)'s numerators and denominator, (3, R, L)."""
    x, y = (ar.cast(c) for c in spans.pixels())
    return ar.add(ar.guard(ar.add(ar.mul(_full(k[:, 0], spans), x), ar.mul(_full(k[:, 1], spans), y))),
                  _full(k[:, 2], spans))


def direct(ar: Arith, k64: np.ndarray, spans: Spans) -> Result:
    return _divide(ar, _direct_form(ar, ar.cast(k64), spans), inside(k64, spans))


def direct_rcp(ar: Arith, k64: np.ndarray, spans: Spans) -> Result:
    return _reciprocal(ar, _direct_form(ar, ar.cast(k64), spans), inside(k64, spans))


def span(ar: Arith, k64: np.ndarray, spans: Spans) -> Result:
    k = ar.cast(k64)
    return _divide(ar, _span_form(ar, k, span_start(ar, k, spans), _n(ar, spans)), inside(k64, spans))


def span_rcp(ar: Arith, k64: np.ndarray, spans: Spans) -> Result:
    k = ar.cast(k64)
    return _reciprocal(ar, _span_form(ar, k, span_start(ar, k, spans), _n(ar, spans)), inside(k64, spans))


def incremental(ar: Arith, k64: np.ndarray, spans: Spans) -> Result:
    k = ar.cast(k64)
    return _divide(ar, ar.running_sum(_steps(span_start(ar, k, spans), k[:, 0], spans.length)), inside(k64, spans))


def parallel(threads: int) -> Callable:
    def evaluate(ar: Arith, k64: np.ndarray, spans: Spans) -> Result:
        k = ar.cast(k64)
        length = spans.length
        rounds = -(-length // threads)
        first = ar.running_sum(_steps(span_start(ar, k, spans), k[:, 0], threads))  # (3, R, threads) by (4)
        stride = ar.mul(k[:, 0], ar.cast(threads))  # exact: threads is a power of two
        seq = np.empty((3, spans.count, rounds, threads), ar.dtype)
        seq[:, :, 0, :] = first
        seq[:, :, 1:, :] = stride[:, None, None, None]
        w = ar.running_sum(seq, axis=2).reshape(3, spans.count, rounds * threads)[:, :, :length]
        return _divide(ar, w, inside(k64, spans))

    return evaluate


def two_ended(ar: Arith, k64: np.ndarray, spans: Spans) -> Result:
    k = ar.cast(k64)
    length = spans.length
    half = (length + 1) // 2  # the left thread's share
    start = span_start(ar, k, spans)
    parts = [ar.running_sum(_steps(start, k[:, 0], half))]
    if length > half:
        end = ar.add(start, ar.mul(k[:, 0:1], ar.cast(length - 1)))
        parts.append(ar.running_sum(_steps(end, -k[:, 0], length - half))[..., ::-1])  # w + (-A) == w - A
    return _divide(ar, np.concatenate(parts, axis=2), inside(k64, spans))


def anchors(length: int, every: int) -> np.ndarray:
    """Span positions evaluated exactly by ``subdivided``: every ``every`` pixels and the last pixel."""
    return np.unique(np.r_[np.arange(0, length, every), length - 1])


def _interpolate(ar: Arith, at: np.ndarray, exact: Result, length: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """u, v and flags (R, length) linear between exact values at the increasing positions ``at`` (first 0, last
    length - 1; ``exact`` holds (R, len(at)) values there, 0 where flagged): value + m * slope in each segment,
    slope = (next - value) / width; a segment with a flagged end is flagged; the last pixel is its anchor's."""
    n = np.arange(length)
    seg = np.minimum(np.searchsorted(at, n, side="right") - 1, at.size - 2)
    width = ar.cast(np.diff(at))
    out = []
    for c in (exact.u, exact.v):
        slope = ar.div(ar.sub(c[:, 1:], c[:, :-1]), width)
        line = ar.add(c[:, seg], ar.mul(ar.cast(np.broadcast_to(n - at[seg], c[:, seg].shape)), slope[:, seg]))
        line[:, -1] = c[:, -1]  # the last pixel is an anchor
        out.append(line)
    flagged = exact.flagged[:, seg] | exact.flagged[:, seg + 1]
    flagged[:, -1] = exact.flagged[:, -1]
    zero = ar.cast(0)
    return np.where(flagged, zero, out[0]), np.where(flagged, zero, out[1]), flagged


def subdivided(every: int) -> Callable:
    def evaluate(ar: Arith, k64: np.ndarray, spans: Spans) -> Result:
        k = ar.cast(k64)
        at = anchors(spans.length, every)
        exact = _divide(ar, _span_form(ar, k, span_start(ar, k, spans), _n(ar, spans, at)), inside(k64, spans)[:, at])
        if at.size == 1:
            return exact
        return Result(*_interpolate(ar, at, exact, spans.length), exact.exact)

    return evaluate


@dataclass(frozen=True)
class SegmentRule:
    """``segment_length``'s per-polygon constants, in the method's precision: with d = D (q's step per pixel),
    m = max(-d, 0), the largest S with |d| S^2 <= 4 (q + min(d, 0) S) / E is 2 (sqrt(m^2 + |d| E q) - m) / (E |d|)."""

    d: np.ndarray  # D
    m: np.ndarray  # max(-D, 0)
    m2: np.ndarray  # m^2
    dE: np.ndarray  # |D| E (exact: E is a power of two)
    scale: np.ndarray  # 2 / (E |D|)


def segment_rule(ar: Arith, k: np.ndarray, fraction: int) -> SegmentRule:
    d = k[2, 0]
    ad, m = np.abs(d), np.maximum(-d, ar.cast(0))
    e = ar.cast(fraction)
    return SegmentRule(d, m, ar.mul(m, m), ar.mul(ad, e), ar.div(ar.cast(2), ar.mul(e, ad)))


def segment_length(ar: Arith, rule: SegmentRule, q: np.ndarray, remaining: np.ndarray) -> np.ndarray:
    """Pixels to the next anchor from an anchor whose denominator is ``q`` (``remaining`` pixels to the span's
    end, at least 1): the largest S whose linear interpolation stays within 1/E of a pixel (docs/perspective.md:
    the error of the chord of u = w / q over S pixels is at most |D| S^2 / (4 min q) pixels of the x footprint),
    at least 1, at most ``remaining``; all of ``remaining`` where D = 0 (u is then affine), 1 where q <= 0."""
    if rule.d == 0:
        return remaining.copy()
    s = ar.mul(ar.sub(ar.sqrt(ar.add(rule.m2, ar.mul(rule.dE, q))), rule.m), rule.scale)
    ok = (q > 0) & (s >= 1)  # NaN fails
    return np.where(ok, np.floor(np.minimum(np.where(ok, s, 1), ar.cast(remaining))), 1).astype(np.int64)


def adaptive(fraction: int) -> Callable:
    def evaluate(ar: Arith, k64: np.ndarray, spans: Spans) -> Result:
        k = ar.cast(k64)
        clip = inside(k64, spans)
        start = span_start(ar, k, spans)
        rule = segment_rule(ar, k, fraction)
        last = spans.length - 1
        found = []  # per step: (spans, positions, exact values there)
        p = np.zeros(spans.count, np.int64)
        active = np.arange(spans.count)
        while active.size:  # one anchor of every span still walking; each step moves at least one pixel
            w = ar.add(start[:, active], ar.mul(k[:, 0:1], ar.cast(p[active])[None]))
            found.append((active, p[active], _divide(ar, w[:, :, None], clip[active, p[active]][:, None])))
            walking = p[active] < last
            active = active[walking]
            if active.size:
                p[active] += segment_length(ar, rule, w[2, walking], last - p[active])
        span = np.concatenate([f[0] for f in found])
        at = np.concatenate([f[1] for f in found])
        order = np.lexsort((at, span))  # every span's anchors in order, span after span
        span, at = span[order], at[order]
        cu, cv, cf = (np.concatenate([getattr(f[2], c)[:, 0] for f in found])[order] for c in ("u", "v", "flagged"))
        if spans.length == 1:
            return Result(cu[:, None], cv[:, None], cf[:, None], at.size)
        # pixel n of span r lies in the segment of the last anchor at or before it; the last pixel, an anchor
        # itself, in the segment before it (methods._interpolate)
        rows = np.arange(spans.count)[:, None]
        pixel = rows * spans.length + np.arange(spans.length)
        seg = np.searchsorted(span * spans.length + at, pixel, side="right") - 1
        seg[:, -1] -= 1
        width = ar.cast(np.diff(at))  # across spans too: those pairs are never used
        out = []
        for c in (cu, cv):
            slope = ar.div(ar.sub(c[1:], c[:-1]), width)
            line = ar.add(c[seg], ar.mul(ar.cast(np.arange(spans.length) - at[seg]), slope[seg]))
            line[:, -1] = c[seg[:, -1] + 1]
            out.append(line)
        flagged = cf[seg] | cf[seg + 1]
        flagged[:, -1] = cf[seg[:, -1] + 1]
        zero = ar.cast(0)
        return Result(np.where(flagged, zero, out[0]), np.where(flagged, zero, out[1]), flagged, at.size)

    return evaluate


def reanchor(every: int) -> Callable:
    def evaluate(ar: Arith, k64: np.ndarray, spans: Spans) -> Result:
        k = ar.cast(k64)
        length = spans.length
        rounds = -(-length // every)
        start = span_start(ar, k, spans)
        fresh = _span_form(ar, k, start, _n(ar, spans, np.arange(rounds) * every))  # (3, R, rounds)
        seq = np.empty((3, spans.count, rounds, every), ar.dtype)
        seq[..., 0] = fresh
        seq[..., 1:] = k[:, 0, None, None, None]
        w = ar.running_sum(seq, axis=3).reshape(3, spans.count, rounds * every)[:, :, :length]
        return _divide(ar, w, inside(k64, spans))

    return evaluate


def kahan(ar: Arith, k64: np.ndarray, spans: Spans) -> Result:
    k = ar.cast(k64)
    step = k[:, 0:1]
    s = span_start(ar, k, spans)
    comp = np.zeros_like(s)
    w = np.empty((*s.shape, spans.length), ar.dtype)
    w[..., 0] = s
    for n in range(1, spans.length):
        y = ar.sub(step, comp)
        t = ar.add(s, y)
        comp = ar.sub(ar.sub(ar.guard(t), s), y)
        s = t
        w[..., n] = s
    return _divide(ar, w, inside(k64, spans))


def split(k64: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(hi, lo) float32 with hi + lo = k64 to about 48 bits."""
    hi = np.asarray(k64, np.float32)
    return hi, (np.asarray(k64, np.float64) - hi).astype(np.float32)


def double_single(ar: Arith, k64: np.ndarray, spans: Spans) -> Result:
    k = ar.cast(k64)
    step_hi, step_lo = (c[:, 0:1] for c in split(k64))
    hi = span_start(ar, k, spans)
    lo = np.zeros_like(hi)
    w = np.empty((*hi.shape, spans.length), ar.dtype)
    w[..., 0] = ar.add(hi, lo)
    for n in range(1, spans.length):
        s = ar.guard(ar.add(hi, step_hi))
        bb = ar.guard(ar.sub(s, hi))
        err = ar.add(ar.sub(hi, ar.sub(s, bb)), ar.sub(step_hi, bb))  # TwoSum's rounding error of hi + step_hi
        e = ar.add(err, ar.add(lo, step_lo))
        hi = ar.guard(ar.add(s, e))
        lo = ar.sub(e, ar.sub(hi, s))
        w[..., n] = ar.add(hi, lo)
    return _divide(ar, w, inside(k64, spans))


@dataclass(frozen=True)
class FixedSetup:
    """16.16 fixed-point start values and steps, with the power-of-two scale of each quantity."""

    starts: np.ndarray  # (3, R) int32
    steps: np.ndarray  # (3,) int32
    ratio: np.ndarray  # (2,) float32: scale(q) / scale(w_u), scale(q) / scale(w_v) (powers of two)


def fixed_setup(k64: np.ndarray, spans: Spans) -> FixedSetup:
    k = np.asarray(k64, np.float64)
    start = k[:, 0:1] * spans.x0 + k[:, 1:2] * spans.y + k[:, 2:3]
    end = start + k[:, 0:1] * (spans.length - 1)
    # The forms are linear: their extremes are at the ends (one step counts too: a 1-pixel span never takes it).
    peak = np.maximum.reduce([np.abs(start).max(1), np.abs(end).max(1), np.abs(k[:, 0])])
    exponents = np.array([math.frexp(FIXED_PEAK / p)[1] - 1 if p > 0 else 0 for p in peak])
    scale = np.ldexp(float(FIXED_ONE), exponents)
    starts = np.rint(start * scale[:, None]).astype(np.int32)
    steps = np.rint(k[:, 0] * scale).astype(np.int32)
    ratio = np.ldexp(1.0, exponents[2] - exponents[:2]).astype(np.float32)
    return FixedSetup(starts, steps, ratio)


def fixed16_16(ar: Arith, k64: np.ndarray, spans: Spans) -> Result:
    fx = fixed_setup(k64, spans)
    seq = np.empty((3, spans.count, spans.length), np.int32)
    seq[..., 0] = fx.starts
    seq[..., 1:] = fx.steps[:, None, None]
    wu, wv, q = ar.cast(ar.int_running_sum(seq))
    u, v = ar.mul(ar.div(wu, q), fx.ratio[0]), ar.mul(ar.div(wv, q), fx.ratio[1])
    ok = (q > 0) & (np.abs(u) <= UMAX) & (np.abs(v) <= UMAX) & inside(k64, spans)
    zero = ar.cast(0)
    return Result(np.where(ok, u, zero), np.where(ok, v, zero), ~ok, q.size)


# --- the registry ---------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Method:
    name: str
    family: str  # FAMILIES
    summary: str
    evaluate: Callable[[Arith, np.ndarray, Spans], Result]
    kernel: str  # its loop: the WGSL kernel (an entry point, or a form of a shared one: kernels.FORMS), compiled.LOOPS
    param: int = 0  # k, S, M or E
    precisions: tuple[str, ...] = ("float32", "float64")
    #: (adds, muls, divs) per texel for u and v together as the paper states them ("implied": by its formula)
    paper_ops: tuple[int, int, int] | None = None
    paper_note: str = ""
    on_gpu: bool = True  # has a WGSL kernel
    #: its operations per texel depend on the geometry (adaptive segments): counted on each configuration instead
    ops_vary: bool = False

    def threads_per_span(self, length: int) -> int:
        """GPU threads per span (0: one thread per pixel)."""
        if self.kernel in PER_PIXEL:
            return 0
        if self.kernel == "parallel":
            return min(self.param, length)
        if self.kernel == "two_ended":
            return 2
        if self.kernel == "subdivided":
            return max(anchors(length, self.param).size - 1, 1)
        return 1


#: The families of methods: the paper's formulas, its formulas with one reciprocal, the approximations (linear
#: between exact anchors: their error is the interpolation's, not rounding), the mitigations of the drift.
FAMILIES = ("paper", "reciprocal", "approximation", "mitigation")
PER_PIXEL = ("direct", "span", "direct_rcp", "span_rcp")  # kernels with one thread per pixel
PARALLEL_THREADS = (2, 4, 8, 16, 32)
SUBDIVISIONS = (8, 16)
ADAPTIVE_FRACTIONS = (8, 32)  # adaptive_E holds the interpolation error to 1/E of a pixel (powers of two)
REANCHOR_EVERY = (16, 64, 256)

_METHODS: list[Method] = [
    Method("direct", "paper", "formula (1) per pixel", direct, "direct", paper_ops=(8, 8, 2), paper_note="stated"),
    Method("span", "paper", "formula (3): per-span constants, ut + A n per pixel", span, "span",
           paper_ops=(4, 4, 2), paper_note="stated"),
    Method("direct_rcp", "reciprocal", "formula (1) with r = 1 / q, u = w_u r, v = w_v r", direct_rcp, "direct_rcp"),
    Method("span_rcp", "reciprocal", "formula (3) with r = 1 / q, u = w_u r, v = w_v r", span_rcp, "span_rcp"),
    Method("incremental", "paper", "formula (4): w += A, q += D, one thread per span", incremental, "incremental",
           paper_ops=(4, 0, 2), paper_note="implied by (4)"),
    *(Method(f"parallel_{k}", "paper", f"formula (5): {k} interleaved threads per span, steps of {k} A",
             parallel(k), "parallel", k, paper_ops=(4, 0, 2), paper_note="implied by (5)") for k in PARALLEL_THREADS),
    Method("two_ended", "paper", "two threads per span, from both ends towards the middle", two_ended, "two_ended",
           paper_ops=(4, 0, 2), paper_note="implied by (4)"),
    *(Method(f"subdivided_{s}", "approximation", f"exact every {s} pixels, linear in between (Quake)",
             subdivided(s), "subdivided", s) for s in SUBDIVISIONS),
    *(Method(f"adaptive_{e}", "approximation", f"exact at anchors spaced so that linear interpolation errs at most "
             f"1/{e} pixel", adaptive(e), "adaptive", e, on_gpu=False, ops_vary=True) for e in ADAPTIVE_FRACTIONS),
    *(Method(f"reanchor_{m}", "mitigation", f"incremental, span form afresh every {m} pixels", reanchor(m),
             "reanchor", m, precisions=("float32",)) for m in REANCHOR_EVERY),
    Method("kahan", "mitigation", "incremental with Kahan-compensated sums", kahan, "kahan", precisions=("float32",)),
    Method("double_single", "mitigation", "incremental with a two-float accumulator and increment", double_single,
           "double_single", precisions=("float32x2",)),
    Method("fixed16_16", "mitigation", "incremental in int32 16.16 fixed point, per-quantity scales", fixed16_16,
           "fixed16_16", precisions=("fixed16.16",)),
]
METHODS: dict[str, Method] = {m.name: m for m in _METHODS}

#: The arithmetic each precision label runs in (the non-float ones do their sums their own way, then divide in f32).
PRECISION_DTYPE = {"float32": np.float32, "float64": np.float64, "float32x2": np.float32, "fixed16.16": np.float32}


def evaluate(name: str, precision: str, coefficients: np.ndarray, spans: Spans) -> tuple[Result, Arith]:
    """Run method ``name`` in ``precision`` on ``spans``; the result and the arithmetic (with its tally)."""
    method = METHODS[name]
    if precision not in method.precisions:
        raise ValueError(f"method {name}: precision {precision!r}; expected one of {', '.join(method.precisions)}")
    ar = Arith(PRECISION_DTYPE[precision])
    return method.evaluate(ar, np.asarray(coefficients, np.float64), spans), ar


@functools.cache
def ops_per_texel(name: str, precision: str | None = None, lengths=(256, 512),
                  fused: bool = False) -> dict[str, tuple[float, float]]:
    """Operations per texel and per span of ``name``, by kind, from running it on one span of two lengths
    (multiples of every k, S and M): {kind: (per texel, per span)}; ``fused``: as FMA hardware executes them
    (``Arith.fused``). Per-polygon work (the k A of the parallel forms) counts as per span. Methods whose counts
    depend on the geometry (``Method.ops_vary``) get this one geometry's."""
    method = METHODS[name]
    precision = precision or method.precisions[0]
    k = np.array([[1.0, 0.1, 3.0], [0.2, 1.0, 5.0], [-1e-4, 1e-5, 1.0]])
    tallies = []
    for length in lengths:
        _, ar = evaluate(name, precision, k, Spans(np.zeros(1, np.int64), np.zeros(1, np.int64), length))
        tallies.append(ar.fused if fused else ar.tally)
    kinds = sorted(set(tallies[0]) | set(tallies[1]))
    out = {}
    for kind in kinds:
        per_texel = (tallies[1][kind] - tallies[0][kind]) / (lengths[1] - lengths[0])
        out[kind] = (per_texel, tallies[0][kind] - per_texel * lengths[0])
    return out
