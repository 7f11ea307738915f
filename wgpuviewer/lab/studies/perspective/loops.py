"""The compiled loops' Python source, for numba (``compiled`` builds and times them): every method as a loop over
spans and pixels in one float type, the per-pixel helpers they call, and ``loop_sources``, which makes the set for a
float type. Each loop is the twin of its numpy form (``methods``): the same operations in the same order.

Every loop takes the same arguments (``compiled.Arguments``): ``k, a_lo, ratio, fx_step, fx_start, x0, y, first,
end, param, out_u, out_v, out_f``. A loop factory takes the helpers (``Helpers``, made once per float type and
build, so that each build compiles its own) and returns the loop; numba freezes what the loop reads from its
closure.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from .geometry import UMAX

#: The most lanes the parallel form keeps (methods.PARALLEL_THREADS).
MAX_LANES = 32


@dataclass(frozen=True)
class Helpers:
    """The float type, its constants and the jitted per-pixel helpers of one set of loops."""

    ftype: type
    zero: object
    one: object
    two: object
    put: Callable  # pixel n from (w_u, w_v, q): the divisions, or 0 and a flag (methods._divide)
    put_rcp: Callable  # the same with one division (methods._reciprocal)
    exact: Callable  # an anchor of the subdivisions: u, v, flag and q at a span position by the span form
    line: Callable  # pixels a .. b - 1 linear between two anchors (methods._interpolate)
    start: Callable  # the per-span constants a x0 + b y + c (methods.span_start)
    span: Callable  # span s's start constants and its clip [lo, hi)
    two_float_step: Callable  # hi + lo plus a + a_lo (methods.double_single)
    advance: Callable  # one step of formula (4): (w_u, w_v, q) + (a_u, a_v, a_q)


def _pixel_helpers(jit, ftype) -> tuple[Callable, Callable, Callable]:
    """put, put_rcp and exact in ``ftype``."""
    zero, one, umax = ftype(0), ftype(1), ftype(UMAX)

    @jit
    def put(ru, rv, rf, n, wu, wv, q, inside):
        ok = (q > zero) & (abs(wu) <= umax * q) & (abs(wv) <= umax * q) & inside
        u = wu / q
        v = wv / q
        ru[n] = u if ok else zero
        rv[n] = v if ok else zero
        rf[n] = not ok

    @jit
    def put_rcp(ru, rv, rf, n, wu, wv, q, inside):
        ok = (q > zero) & (abs(wu) <= umax * q) & (abs(wv) <= umax * q) & inside
        r = one / q
        u = wu * r
        v = wv * r
        ru[n] = u if ok else zero
        rv[n] = v if ok else zero
        rf[n] = not ok

    @jit
    def exact(su, sv, sq, au, av, aq, p, inside):
        pf = ftype(p)
        wu = su + au * pf
        wv = sv + av * pf
        q = sq + aq * pf
        ok = (q > zero) & (abs(wu) <= umax * q) & (abs(wv) <= umax * q) & inside
        u = wu / q
        v = wv / q
        return (u if ok else zero), (v if ok else zero), not ok, q

    return put, put_rcp, exact


def helpers(jit, ftype) -> Helpers:
    """The helpers of a set of loops in ``ftype``, compiled with ``jit``."""
    zero = ftype(0)

    @jit
    def line(ru, rv, rf, a, b, cu, cv, cf, du, dv, df):
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
        xf, yf = ftype(x0), ftype(y)
        return ((k[0, 0] * xf + k[0, 1] * yf) + k[0, 2], (k[1, 0] * xf + k[1, 1] * yf) + k[1, 2],
                (k[2, 0] * xf + k[2, 1] * yf) + k[2, 2])

    @jit
    def span(k, x0, y, first, end, s):
        su, sv, sq = start(k, x0[s], y[s])
        return su, sv, sq, first[s], end[s]

    @jit
    def two_float_step(h, lo, a, a_lo):
        sm = h + a
        bb = sm - h
        err = (h - (sm - bb)) + (a - bb)
        e = err + (lo + a_lo)
        h2 = sm + e
        return h2, e - (h2 - sm)

    @jit
    def advance(wu, wv, q, au, av, aq):
        return wu + au, wv + av, q + aq

    put, put_rcp, exact = _pixel_helpers(jit, ftype)
    return Helpers(ftype, zero, ftype(1), ftype(2), put, put_rcp, exact, line, start, span, two_float_step, advance)


# --- the per-pixel forms: every pixel from the plane equations -----------------------------------------------------


def direct_like(store: Callable, ftype) -> Callable:
    """Formula (1) per pixel, ``store`` dividing (put or put_rcp)."""

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


def span_like(store: Callable, h: Helpers) -> Callable:
    """Formula (3): the span's start constants plus n steps, per pixel."""
    span, ftype = h.span, h.ftype

    def loop(k, a_lo, ratio, fx_step, fx_start, x0, y, first, end, param, out_u, out_v, out_f):
        au, av, aq = k[0, 0], k[1, 0], k[2, 0]
        length = out_u.shape[1]
        for s in range(x0.size):
            ru, rv, rf = out_u[s], out_v[s], out_f[s]
            su, sv, sq, lo, hi = span(k, x0, y, first, end, s)
            for n in range(length):
                nf = ftype(n)
                store(ru, rv, rf, n, su + au * nf, sv + av * nf, sq + aq * nf, (n >= lo) & (n < hi))
    return loop


def fixed16_16(h: Helpers) -> Callable:
    """Fixed-point 16.16 sums (int32, wrapping), converted and divided per pixel."""
    zero, umax = h.zero, h.ftype(UMAX)
    ftype = h.ftype

    def loop(k, a_lo, ratio, fx_step, fx_start, x0, y, first, end, param, out_u, out_v, out_f):
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
    return loop


# --- the running sums: formula (4), one step per pixel ----------------------------------------------------------


def running(h: Helpers, init: Callable, emit: Callable, step: Callable) -> Callable:
    """A running sum from each span's start: ``init(su, sv, sq)`` its state, ``emit(state)`` the (w_u, w_v, q) a
    pixel divides, ``step(state, a)`` the state at the next pixel (a: the x coefficients, then their low parts)."""
    put, span = h.put, h.span

    def loop(k, a_lo, ratio, fx_step, fx_start, x0, y, first, end, param, out_u, out_v, out_f):
        a = (k[0, 0], k[1, 0], k[2, 0], a_lo[0], a_lo[1], a_lo[2])
        length = out_u.shape[1]
        for s in range(x0.size):
            ru, rv, rf = out_u[s], out_v[s], out_f[s]
            su, sv, sq, lo, hi = span(k, x0, y, first, end, s)
            state = init(su, sv, sq)
            for n in range(length):
                wu, wv, q = emit(state)
                put(ru, rv, rf, n, wu, wv, q, (n >= lo) & (n < hi))
                state = step(state, a)
    return loop


def running_sums(jit, h: Helpers) -> dict[str, tuple[Callable, Callable, Callable]]:
    """(init, emit, step) of the plain running sum (formula (4)) and the two-float one (hi + lo, with the
    increment's low part)."""
    zero, two_float_step = h.zero, h.two_float_step

    @jit
    def plain(su, sv, sq):
        return su, sv, sq

    @jit
    def plain_step(w, a):
        return w[0] + a[0], w[1] + a[1], w[2] + a[2]

    @jit
    def two_float_init(su, sv, sq):
        return su, sv, sq, zero, zero, zero

    @jit
    def sums(w):
        return w[0], w[1], w[2]

    @jit
    def two_float_emit(w):
        return w[0] + w[3], w[1] + w[4], w[2] + w[5]

    @jit
    def two_float(w, a):
        hu, ou = two_float_step(w[0], w[3], a[0], a[3])
        hv, ov = two_float_step(w[1], w[4], a[1], a[4])
        hq, oq = two_float_step(w[2], w[5], a[2], a[5])
        return hu, hv, hq, ou, ov, oq

    return {"incremental": (plain, sums, plain_step), "double_single": (two_float_init, two_float_emit, two_float)}


def parallel(h: Helpers) -> Callable:
    """k lanes, each stepping k pixels at a time from its own start."""
    put, span, advance, ftype = h.put, h.span, h.advance, h.ftype

    def loop(k, a_lo, ratio, fx_step, fx_start, x0, y, first, end, param, out_u, out_v, out_f):
        au, av, aq = k[0, 0], k[1, 0], k[2, 0]
        lanes = min(max(param, 1), MAX_LANES)
        stride_u, stride_v, stride_q = au * ftype(lanes), av * ftype(lanes), aq * ftype(lanes)
        lane_u, lane_v, lane_q = np.empty(MAX_LANES, ftype), np.empty(MAX_LANES, ftype), np.empty(MAX_LANES, ftype)
        length = out_u.shape[1]
        for s in range(x0.size):
            ru, rv, rf = out_u[s], out_v[s], out_f[s]
            wu, wv, q, lo, hi = span(k, x0, y, first, end, s)
            for j in range(lanes):  # lane j starts at w_j, by j steps of formula (4)
                lane_u[j], lane_v[j], lane_q[j] = wu, wv, q
                wu, wv, q = advance(wu, wv, q, au, av, aq)
            for base in range(0, length, lanes):
                for j in range(min(lanes, length - base)):
                    n = base + j
                    put(ru, rv, rf, n, lane_u[j], lane_v[j], lane_q[j], (n >= lo) & (n < hi))
                    lane_u[j] = lane_u[j] + stride_u
                    lane_v[j] = lane_v[j] + stride_v
                    lane_q[j] = lane_q[j] + stride_q
    return loop


def two_ended(h: Helpers) -> Callable:
    """Half the span from each end; w + (-a) is w - a exactly."""
    put, span, advance, ftype = h.put, h.span, h.advance, h.ftype

    def loop(k, a_lo, ratio, fx_step, fx_start, x0, y, first, end, param, out_u, out_v, out_f):
        au, av, aq = k[0, 0], k[1, 0], k[2, 0]
        length = out_u.shape[1]
        half = (length + 1) // 2
        last = ftype(length - 1)
        for s in range(x0.size):
            ru, rv, rf = out_u[s], out_v[s], out_f[s]
            su, sv, sq, lo, hi = span(k, x0, y, first, end, s)
            wu, wv, q = su, sv, sq
            for n in range(half):
                put(ru, rv, rf, n, wu, wv, q, (n >= lo) & (n < hi))
                wu, wv, q = advance(wu, wv, q, au, av, aq)
            wu, wv, q = su + au * last, sv + av * last, sq + aq * last
            for i in range(length - half):
                n = length - 1 - i
                put(ru, rv, rf, n, wu, wv, q, (n >= lo) & (n < hi))
                wu, wv, q = advance(wu, wv, q, -au, -av, -aq)
    return loop


def reanchor(h: Helpers) -> Callable:
    """The running sum, set to the span form every ``param`` pixels."""
    put, span, advance, ftype = h.put, h.span, h.advance, h.ftype

    def loop(k, a_lo, ratio, fx_step, fx_start, x0, y, first, end, param, out_u, out_v, out_f):
        au, av, aq = k[0, 0], k[1, 0], k[2, 0]
        every = max(param, 1)
        length = out_u.shape[1]
        for s in range(x0.size):
            ru, rv, rf = out_u[s], out_v[s], out_f[s]
            su, sv, sq, lo, hi = span(k, x0, y, first, end, s)
            wu, wv, q = su, sv, sq
            for n in range(length):
                if n % every == 0:
                    nf = ftype(n)
                    wu, wv, q = su + au * nf, sv + av * nf, sq + aq * nf
                put(ru, rv, rf, n, wu, wv, q, (n >= lo) & (n < hi))
                wu, wv, q = advance(wu, wv, q, au, av, aq)
    return loop


def kahan(h: Helpers) -> Callable:
    """Compensated (Kahan) running sums."""
    put, span, zero = h.put, h.span, h.zero

    def loop(k, a_lo, ratio, fx_step, fx_start, x0, y, first, end, param, out_u, out_v, out_f):
        au, av, aq = k[0, 0], k[1, 0], k[2, 0]
        length = out_u.shape[1]
        for s in range(x0.size):
            wu, wv, q, lo, hi = span(k, x0, y, first, end, s)
            cu = cv = cq = zero
            ru, rv, rf = out_u[s], out_v[s], out_f[s]
            for n in range(length):
                put(ru, rv, rf, n, wu, wv, q, (n >= lo) & (n < hi))
                yu, yv, yq = au - cu, av - cv, aq - cq
                tu, tv, tq = wu + yu, wv + yv, q + yq
                cu, cv, cq = (tu - wu) - yu, (tv - wv) - yv, (tq - q) - yq
                wu, wv, q = tu, tv, tq
    return loop


# --- the subdivisions: exact anchors, linear segments between them ------------------------------------------------


def segmented(h: Helpers, rule: Callable, segment: Callable) -> Callable:
    """Anchors by the span form, pixels between them linear; ``rule(aq, param)`` gives the constants of
    ``segment(constants, a, length, q)``, the next anchor after ``a`` (q: the span form's q at ``a``)."""
    span, exact, line = h.span, h.exact, h.line

    def loop(k, a_lo, ratio, fx_step, fx_start, x0, y, first, end, param, out_u, out_v, out_f):
        au, av, aq = k[0, 0], k[1, 0], k[2, 0]
        constants = rule(aq, param)
        length = out_u.shape[1]
        for s in range(x0.size):
            ru, rv, rf = out_u[s], out_v[s], out_f[s]
            su, sv, sq, lo, hi = span(k, x0, y, first, end, s)
            cu, cv, cf, q = exact(su, sv, sq, au, av, aq, 0, (lo <= 0) & (hi > 0))
            a = 0
            while a < length - 1:
                b = segment(constants, a, length, q)
                du, dv, df, q = exact(su, sv, sq, au, av, aq, b, (b >= lo) & (b < hi))
                line(ru, rv, rf, a, b, cu, cv, cf, du, dv, df)
                a, cu, cv, cf = b, du, dv, df
            ru[length - 1] = cu
            rv[length - 1] = cv
            rf[length - 1] = cf
    return loop


def segment_rules(jit, h: Helpers) -> dict[str, tuple[Callable, Callable]]:
    """The subdivisions' (rule, segment): every ``param`` pixels, or adaptive (methods.segment_rule and
    methods.segment_length)."""
    ftype, zero, one, two = h.ftype, h.zero, h.one, h.two

    @jit
    def every_rule(aq, param):
        return max(param, 1)

    @jit
    def every_segment(every, a, length, q):
        return min(a + every, length - 1)

    @jit
    def adaptive_rule(aq, param):
        ad = abs(aq)
        m = -aq if aq < zero else zero
        e = ftype(param)
        return ad, m, m * m, ad * e, two / (e * ad)

    @jit
    def adaptive_segment(constants, a, length, q):
        ad, m, m2, de, scale = constants
        remaining = length - 1 - a
        step = 1
        if ad == zero:
            step = remaining
        elif q > zero:
            sl = (np.sqrt(m2 + de * q) - m) * scale
            if sl >= one:
                step = int(np.floor(min(sl, ftype(remaining))))
        return a + step

    return {"subdivided": (every_rule, every_segment), "adaptive": (adaptive_rule, adaptive_segment)}


def loop_sources(jit, ftype) -> dict[str, Callable]:
    """Every loop (by ``Method.kernel``) as a Python function in the float type ``ftype`` (np.float32 or
    np.float64), for numba; its helpers compiled with ``jit`` when the first loop calling them is."""
    h = helpers(jit, ftype)
    rules, sums = segment_rules(jit, h), running_sums(jit, h)
    return {"direct": direct_like(h.put, ftype), "direct_rcp": direct_like(h.put_rcp, ftype),
            "span": span_like(h.put, h), "span_rcp": span_like(h.put_rcp, h),
            "incremental": running(h, *sums["incremental"]), "parallel": parallel(h), "two_ended": two_ended(h),
            "subdivided": segmented(h, *rules["subdivided"]), "adaptive": segmented(h, *rules["adaptive"]),
            "reanchor": reanchor(h), "kahan": kahan(h),
            "double_single": running(h, *sums["double_single"]), "fixed16_16": fixed16_16(h)}
