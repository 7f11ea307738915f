"""The numpy forms of the methods: float64 agreement, float32 drift against span length (measured and against the
rounding bound each form implies), the mitigations' bounds, the one-reciprocal forms, the adaptive subdivision and
its error bound, the hard cases (edge-on, past the horizon, short and odd spans) and the operation counts (as
written, and with fused multiply-adds)."""

from __future__ import annotations

import numpy as np
import pytest

from wgpuviewer.lab.studies.perspective import geometry as g
from wgpuviewer.lab.studies.perspective import methods as M
from wgpuviewer.lab.studies.perspective.arith import Arith
from wgpuviewer.lab.studies.perspective.run import instances  # imports wgpu before the log fixture touches its logger

PAPER = [name for name, m in M.METHODS.items() if m.family == "paper"]
RECIPROCAL = [name for name, m in M.METHODS.items() if m.family == "reciprocal"]
ADAPTIVE = [f"adaptive_{e}" for e in M.ADAPTIVE_FRACTIONS]
DRIFT = g.Setup(span_length=8192, rows=2, tilt=80.0)


def error(name: str, precision: str, quad: g.Quad, ref: g.Reference | None = None) -> np.ndarray:
    """Per-pixel texel error against float64 where both are defined (NaN elsewhere)."""
    ref = ref or g.reference(quad.coefficients, quad.spans)
    result, _ = M.evaluate(name, precision, quad.coefficients, quad.spans)
    err = np.hypot(result.u - ref.u, result.v - ref.v)
    return np.where(ref.valid & ~result.flagged, err, np.nan)


@pytest.fixture(scope="module")
def drift_quad():
    return g.build(DRIFT)


# --- float64 -----------------------------------------------------------------------------------------------------

@pytest.mark.parametrize("setup", [
    g.Setup(span_length=1920, rows=4, tilt=60.0), g.Setup(span_length=1920, rows=4, tilt=80.0),
    g.Setup(span_length=343, rows=5, tilt=85.0), g.Setup(span_length=1920, rows=3, tilt=80.0, offset=1e3),
])
def test_float64_forms_agree_with_direct_to_1e_9_texel(setup):
    quad = g.build(setup)
    ref = g.reference(quad.coefficients, quad.spans)
    for name in PAPER + RECIPROCAL:
        assert np.nanmax(error(name, "float64", quad, ref)) <= 1e-9, name


def test_float64_drift_follows_the_float32_law_scaled_by_2_to_the_minus_29(drift_quad):
    """Past ~2000 pixels float64 incremental sums drift beyond 1e-9 texel too, by the same n * ulp law."""
    f64 = np.nanmax(error("incremental", "float64", drift_quad))
    f32 = np.nanmax(error("incremental", "float32", drift_quad))
    assert 1e-10 < f64 < 1e-8
    assert f32 / f64 == pytest.approx(2.0**29, rel=0.9)  # float32 has 29 bits fewer


def test_subdivided_is_exact_at_its_anchors_and_an_approximation_between():
    quad = g.build(g.Setup(span_length=100, rows=3, tilt=80.0))
    ref = g.reference(quad.coefficients, quad.spans)
    for every in M.SUBDIVISIONS:
        err = error(f"subdivided_{every}", "float64", quad, ref)
        at = M.anchors(100, every)
        assert np.nanmax(err[:, at]) <= 1e-9
        assert np.nanmax(err) > 1e-3  # perspective is not affine: the error between anchors is real


# --- one reciprocal ----------------------------------------------------------------------------------------------

@pytest.mark.parametrize("name, twin", [("direct_rcp", "direct"), ("span_rcp", "span")])
def test_one_reciprocal_is_within_two_ulps_of_the_two_divisions(name, twin):
    """u = w_u (1 / q) rounds twice where w_u / q rounds once: at most 1.5 ulp apart in exact arithmetic, so within
    2 ulp of the divided value, with the same flags; and it is a different computation (some pixels differ)."""
    quad = g.build(g.Setup(span_length=1920, rows=4, tilt=85.0, offset=1e3))
    rcp, _ = M.evaluate(name, "float32", quad.coefficients, quad.spans)
    div, _ = M.evaluate(twin, "float32", quad.coefficients, quad.spans)
    assert np.array_equal(rcp.flagged, div.flagged)
    for a, b in ((rcp.u, div.u), (rcp.v, div.v)):
        assert (np.abs(a.astype(np.float64) - b) <= 2 * _ulp(b)).all()
    assert (rcp.u != div.u).any()


# --- adaptive subdivision ----------------------------------------------------------------------------------------

def test_the_chord_error_in_pixels_is_the_closed_form_and_within_the_bound():
    """docs/perspective.md: for u = (w0 + a t) / (q0 + d t), the chord between t = 0 and t = S errs by
    G d t (S - t) / (q0 qS q(t)) (G = a q0 - d w0), which over the x footprint |G| / q(t)^2 is
    |d| t (S - t) q(t) / (q0 qS) pixels, at most |d| S^2 / (4 min(q0, qS))."""
    rng = np.random.default_rng(3)
    for _ in range(200):
        w0, a = rng.uniform(-1e3, 1e3), rng.uniform(-2, 2)
        q0, d = rng.uniform(0.1, 2.0), rng.uniform(-1e-2, 1e-2)
        span = rng.integers(2, 60)
        if q0 + d * span <= 0:
            continue
        t = np.linspace(0.0, span, 2001)
        q, qs = q0 + d * t, q0 + d * span
        u = (w0 + a * t) / q
        chord = w0 / q0 + t / span * ((w0 + a * span) / qs - w0 / q0)
        footprint = np.abs(a * q0 - d * w0) / q**2
        pixels = np.abs(u - chord) / footprint
        closed = np.abs(d) * t * (span - t) * q / (q0 * qs)
        np.testing.assert_allclose(pixels, closed, rtol=1e-6, atol=1e-9)
        bound = abs(d) * span**2 / (4 * min(q0, qs))
        assert pixels.max() <= bound * (1 + 1e-9)
        if abs(d) * span / min(q0, qs) < 1e-3:  # tight when q barely changes over the segment
            assert pixels.max() >= 0.99 * bound


def _within_bound(d: float, q: np.ndarray, fraction: int, steps: np.ndarray) -> np.ndarray:
    """|d| S^2 <= 4 min(q, q + d S) / E: the chord over S pixels errs at most 1/E pixel."""
    return abs(d) * steps**2 <= 4 * (q + min(d, 0.0) * steps) / fraction * (1 + 1e-12)


def test_segment_length_is_the_longest_the_bound_allows():
    ar = Arith(np.float64)
    rng = np.random.default_rng(5)
    for _ in range(100):
        d = rng.choice([-1.0, 1.0]) * 10 ** rng.uniform(-6, -2)
        fraction = int(rng.choice(M.ADAPTIVE_FRACTIONS))
        k = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [d, 0.0, 1.0]])
        rule = M.segment_rule(ar, k, fraction)
        q = 10 ** rng.uniform(-1, 0, 8)
        remaining = np.full(8, 10**6)
        steps = M.segment_length(ar, rule, q, remaining)
        assert (_within_bound(d, q, fraction, steps) | (steps == 1)).all()  # one pixel: no interpolation at all
        assert not _within_bound(d, q, fraction, steps + 1).any()
    assert (M.segment_length(ar, rule, np.array([-1.0, 0.0]), np.array([9, 9])) == 1).all()  # no anchor to trust
    affine = M.segment_rule(ar, np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]), 8)
    assert (M.segment_length(ar, affine, np.array([1.0]), np.array([77])) == 77).all()  # D = 0: u is affine


@pytest.mark.parametrize("tilt", [30.0, 80.0, 89.0, 89.9, 95.0])
def test_adaptive_holds_its_error_below_its_fraction_of_a_pixel(tilt):
    """The bound is the interpolation's; float32 rounding adds at most what `direct` itself errs, twice over."""
    quad = g.build(g.Setup(span_length=1920, rows=3, tilt=tilt))
    ref = g.reference(quad.coefficients, quad.spans)
    rounding = 2 * np.nanmax(error("direct", "float32", quad, ref) / ref.footprint)
    for name in ADAPTIVE:
        pixels = error(name, "float32", quad, ref) / ref.footprint
        assert np.nanmax(pixels) <= 1 / M.METHODS[name].param + rounding, name
        assert np.nanmax(pixels) >= 0.5 / M.METHODS[name].param, name  # and uses the room it has


def test_adaptive_spends_anchors_where_q_changes_fast():
    exact = {}
    for tilt in (30.0, 80.0, 89.9):
        quad = g.build(g.Setup(span_length=1920, rows=3, tilt=tilt))
        for name in ADAPTIVE:
            exact[name, tilt] = M.evaluate(name, "float32", quad.coefficients, quad.spans)[0].exact
    for name in ADAPTIVE:
        assert exact[name, 30.0] < exact[name, 80.0] < exact[name, 89.9], name
    assert all(exact[ADAPTIVE[0], t] < exact[ADAPTIVE[-1], t] for t in (30.0, 80.0, 89.9))  # a finer bound costs more
    flat = np.array([[1.0, 0.1, 3.0], [0.2, 1.0, 5.0], [0.0, 0.0, 1.0]])  # D = E = 0: an affine map
    spans = g.Spans(np.zeros(4, np.int64), np.arange(4, dtype=np.int64), 500)
    result, _ = M.evaluate(ADAPTIVE[0], "float64", flat, spans)
    assert result.exact == 2 * 4  # both ends of every span
    np.testing.assert_allclose(result.u, g.reference(flat, spans).u, rtol=0, atol=1e-9)


def test_adaptive_is_exact_at_its_anchors():
    """Float64: the anchors are the span form; between them the error is the chord's."""
    quad = g.build(g.Setup(span_length=1000, rows=2, tilt=89.0))
    ref = g.reference(quad.coefficients, quad.spans)
    for name in ADAPTIVE:
        err = error(name, "float64", quad, ref)
        assert np.nanmax(err[:, [0, -1]]) <= 1e-9
        assert np.nanmax(err / ref.footprint) <= 1 / M.METHODS[name].param * (1 + 1e-6)


# --- float32 drift -----------------------------------------------------------------------------------------------

def test_float32_incremental_drift_grows_with_span_length_while_direct_does_not():
    """Pooled over four geometries (the rounding pattern of one geometry can cancel for a while)."""
    lengths = (256, 1920, 8192)
    incremental, direct = [], []
    for n in lengths:
        quads = [g.build(s) for s in instances(g.Setup(span_length=n, rows=2, tilt=80.0), 4)]
        incremental.append(max(np.nanmax(error("incremental", "float32", q)) for q in quads))
        direct.append(max(np.nanmax(error("direct", "float32", q)) for q in quads))
    # measured on these geometries: 0.051, 0.12, 2.6 texels incremental; 0.0011 to 0.0017 direct
    assert incremental[2] >= 1.0 and incremental[2] >= 20 * incremental[0] and incremental[2] >= 5 * incremental[1]
    assert max(direct) <= 5e-3 and max(direct) <= 3 * min(direct)
    slope = np.polyfit(np.log(lengths), np.log(incremental), 1)[0]
    assert 0.6 <= slope <= 1.8  # about linear: the same increment rounds the same way step after step


def test_k_parallel_and_two_ended_cut_the_drift(drift_quad):
    base = np.nanmax(error("incremental", "float32", drift_quad))
    assert np.nanmax(error("two_ended", "float32", drift_quad)) < base / 4
    for k in M.PARALLEL_THREADS:
        assert np.nanmax(error(f"parallel_{k}", "float32", drift_quad)) < base / 2, k


def test_parallel_with_one_thread_is_incremental():
    quad = g.build(g.Setup(span_length=777, rows=3, tilt=85.0, offset=1e4))
    for precision in (np.float32, np.float64):
        one = M.parallel(1)(Arith(precision), quad.coefficients, quad.spans)
        incremental = M.incremental(Arith(precision), quad.coefficients, quad.spans)
        np.testing.assert_array_equal(one.u, incremental.u)
        np.testing.assert_array_equal(one.v, incremental.v)


def _ulp(x) -> np.ndarray:
    return np.spacing(np.abs(np.asarray(x, np.float32))).astype(np.float64)


def drift_bound(quad: g.Quad, steps: np.ndarray, exact_step: bool = False, start_ops: int = 4) -> np.ndarray:
    """A per-pixel bound on the float32 error of a running-sum form with ``steps`` (R, L) rounded additions behind
    each pixel: each addition rounds by at most half an ulp of the largest value in the span, the start value by
    ``start_ops`` half-ulps, the float32 coefficients differ from float64 by half an ulp (unless ``exact_step``: the
    step is carried to float64 accuracy), and the division adds one ulp of the result. First order in the errors."""
    k = quad.coefficients
    x, y = quad.spans.pixels()
    w = g.numerators(k, quad.spans)
    coefficient_error = np.abs(k.astype(np.float32).astype(np.float64) - k)
    if exact_step:
        coefficient_error[:, 0] = 0.0
    dw = []
    for i in range(3):
        peak = np.max([np.abs(w[i]), np.abs(k[i, 0] * x), np.abs(k[i, 1] * y), np.full(x.shape, abs(k[i, 2]))], 0)
        half_ulp = _ulp(peak.max(axis=1, keepdims=True)) / 2
        dw.append((steps + start_ops) * half_ulp + coefficient_error[i, 0] * np.abs(x)
                  + coefficient_error[i, 1] * np.abs(y) + coefficient_error[i, 2])
    u, v = w[0] / w[2], w[1] / w[2]
    denominator = np.abs(w[2]) - dw[2]
    du = (dw[0] + np.abs(u) * dw[2]) / denominator + _ulp(u)
    dv = (dw[1] + np.abs(v) * dw[2]) / denominator + _ulp(v)
    return np.where(denominator > 0, np.hypot(du, dv), np.inf)


def _steps(name: str, length: int, rows: int) -> np.ndarray:
    """Rounded additions behind pixel n in each form (its structure: what each thread walks)."""
    n = np.arange(length)
    if name in ("direct", "span"):
        s = np.zeros(length)
    elif name == "incremental":
        s = n
    elif name.startswith("parallel_"):
        k = int(name.split("_")[1])
        s = np.minimum(n, k - 1) + np.maximum(n - (k - 1), 0) // k + 1  # the prefix by (4), then strides
    elif name == "two_ended":
        half = (length + 1) // 2
        s = np.where(n < half, n, length - 1 - n) + 2  # the far end starts by the span form
    elif name.startswith("reanchor_"):
        s = n % int(name.split("_")[1]) + 2
    else:
        raise AssertionError(name)
    return np.broadcast_to(s, (rows, length))


@pytest.mark.parametrize("name", ["direct", "span", "incremental", *(f"parallel_{k}" for k in M.PARALLEL_THREADS),
                                  "two_ended", *(f"reanchor_{m}" for m in M.REANCHOR_EVERY)])
@pytest.mark.parametrize("setup", [DRIFT, g.Setup(span_length=1920, rows=3, tilt=89.0, offset=1e5)])
def test_every_running_sum_stays_within_its_rounding_bound(name, setup):
    """The drift is what the number of rounded steps behind each pixel predicts (and re-anchoring every M pixels
    bounds it to M steps), never more."""
    quad = g.build(setup)
    err = error(name, "float32", quad)
    bound = drift_bound(quad, _steps(name, setup.span_length, setup.rows))
    ok = np.isfinite(err)
    assert ok.mean() > 0.99
    assert (err[ok] <= bound[ok]).all(), float(np.max(err[ok] / bound[ok]))


@pytest.mark.parametrize("setup", [DRIFT, g.Setup(span_length=1920, rows=3, tilt=89.0, offset=1e5)])
def test_compensated_sums_bound_the_drift_to_a_few_roundings_at_any_length(setup):
    """Kahan: the sum of the float32 steps to a few ulps, whatever the length; double-single: the float64 step to
    a few ulps (so it also carries the step's float32 rounding away)."""
    quad = g.build(setup)
    steps = np.full((setup.rows, setup.span_length), 4.0)
    for name, exact_step in (("kahan", False), ("double_single", True)):
        err = error(name, M.METHODS[name].precisions[0], quad)
        bound = drift_bound(quad, steps, exact_step=exact_step)
        ok = np.isfinite(err)
        assert (err[ok] <= bound[ok]).all(), (name, float(np.max(err[ok] / bound[ok])))
    incremental = np.nanmax(error("incremental", "float32", quad))
    assert np.nanmax(error("kahan", "float32", quad)) < incremental / 50


def test_fixed_point_error_is_bounded_by_its_quantum_per_step():
    """16.16 sums are exact integer arithmetic: the error is half a unit for the start plus half a unit per step,
    in each quantity's scale, then float32 conversion and division."""
    quad = g.build(DRIFT)
    fx = M.fixed_setup(quad.coefficients, quad.spans)
    scale = np.ldexp(1.0, np.log2(np.abs(fx.steps / quad.coefficients[:, 0])).round().astype(int))
    w = g.numerators(quad.coefficients, quad.spans)
    n = np.arange(DRIFT.span_length)
    dw = [(0.5 + 0.5 * n) / scale[i] + _ulp(np.abs(w[i]).max() * scale[i]) / scale[i] for i in range(3)]
    u, v = w[0] / w[2], w[1] / w[2]
    bound = np.hypot((dw[0] + np.abs(u) * dw[2]) / (w[2] - dw[2]) + 2 * _ulp(u),
                     (dw[1] + np.abs(v) * dw[2]) / (w[2] - dw[2]) + 2 * _ulp(v))
    err = error("fixed16_16", "fixed16.16", quad)
    assert (err <= bound).all(), float(np.max(err / bound))
    assert np.nanmax(err) < np.nanmax(error("incremental", "float32", quad)) / 10


# --- hard cases ----------------------------------------------------------------------------------------------------

@pytest.mark.parametrize("tilt", [89.9, 90.0, 95.0, 120.0, 170.0])
def test_edge_on_and_past_the_horizon_every_output_is_finite_and_undefined_texels_are_flagged(tilt):
    quad = g.build(g.Setup(span_length=700, rows=3, tilt=tilt))
    ref = g.reference(quad.coefficients, quad.spans)
    for name, method in M.METHODS.items():
        for precision in method.precisions:
            result, _ = M.evaluate(name, precision, quad.coefficients, quad.spans)
            assert np.isfinite(result.u).all() and np.isfinite(result.v).all(), (name, precision)
            assert not (~ref.valid & ~result.flagged).any(), (name, precision)  # no silent garbage texel
            assert (result.u[result.flagged] == 0).all()
            # the span clip's guard band flags a little more than the reference's undefined pixels (subdivided:
            # up to the whole subdivision next to it), no more
            assert (result.flagged & ref.valid).mean() <= 0.01 + method.param / 700, (name, precision)


def test_a_span_through_the_eye_plane_keeps_stepping_correctly_after_the_crossing():
    """Incremental sums walk through q <= 0 without harm: pixels before the crossing are as accurate as ever."""
    quad = g.build(g.Setup(span_length=1000, rows=2, tilt=95.0))
    ref = g.reference(quad.coefficients, quad.spans)
    assert 0.5 < ref.valid.mean() < 1.0
    err = error("incremental", "float32", quad, ref)
    assert np.nanmax(err[:, :100]) < 0.01


@pytest.mark.parametrize("length", [1, 2, 3, 17, 343])
def test_short_odd_and_offset_spans(length):
    """Spans of any length starting anywhere in a 1000 x 20 frame (not only at x = 0)."""
    rng = np.random.default_rng(length)
    quad = g.build(g.Setup(span_length=1000, rows=20, tilt=70.0))
    spans = g.Spans(rng.integers(0, 1000 - length + 1, 5), rng.integers(0, 20, 5), length)
    ref = g.reference(quad.coefficients, spans)
    for name, method in M.METHODS.items():
        result, _ = M.evaluate(name, method.precisions[0], quad.coefficients, spans)
        assert result.u.shape == (5, length)
        assert not result.flagged.any()
        tolerance = 1.0 if method.family == "approximation" else 0.05  # linear between anchors
        assert np.hypot(result.u - ref.u, result.v - ref.v).max() < tolerance, name


def test_the_running_sums_add_left_to_right_as_the_formula_does():
    """np.add.accumulate in float32 is the scalar recurrence w_n = w_{n-1} + a, bit for bit; np.sum is not."""
    rng = np.random.default_rng(4)
    start, step = np.float32(rng.uniform(100, 200)), np.float32(rng.uniform(0, 1))
    seq = np.full(5000, step, np.float32)
    seq[0] = start
    w = np.float32(start)
    scalar = [w]
    for _ in range(4999):
        w = np.float32(w + step)
        scalar.append(w)
    ar = Arith(np.float32)
    np.testing.assert_array_equal(ar.running_sum(seq), np.array(scalar, np.float32))
    assert np.sum(seq, dtype=np.float32) != scalar[-1]  # pairwise summation: a different (better) algorithm


def test_evaluate_refuses_a_precision_the_method_does_not_have():
    quad = g.build(g.Setup(span_length=8, rows=1, tilt=45.0))
    with pytest.raises(ValueError, match="precision"):
        M.evaluate("kahan", "float64", quad.coefficients, quad.spans)


# --- operation counts ----------------------------------------------------------------------------------------------

#: (add, mul, div, guard, int add) per texel for u and v together, as the code does them (docs/perspective.md).
CODE_OPS = {
    "direct": (6, 6, 2, 3, 0), "span": (3, 3, 2, 0, 0), "incremental": (3, 0, 2, 0, 0), "two_ended": (3, 0, 2, 0, 0),
    "direct_rcp": (6, 8, 1, 3, 0), "span_rcp": (3, 5, 1, 0, 0),
    **{f"parallel_{k}": (3, 0, 2, 0, 0) for k in M.PARALLEL_THREADS},
    "kahan": (12, 0, 2, 3, 0), "double_single": (36, 0, 2, 9, 0), "fixed16_16": (0, 2, 2, 0, 3),
}


@pytest.mark.parametrize("name", list(CODE_OPS))
def test_operation_counts_per_texel_come_from_the_code(name):
    ops = M.ops_per_texel(name)
    got = tuple(ops.get(kind, (0.0, 0.0))[0] for kind in ("add", "mul", "div", "guard", "int_add"))
    assert got == pytest.approx(CODE_OPS[name], abs=1e-9)


#: (add, mul, fma, div) per texel with each product fused into the one addition that uses it.
FUSED_OPS = {
    "direct": (3, 3, 3, 2), "span": (0, 0, 3, 2), "incremental": (3, 0, 0, 2), "direct_rcp": (3, 5, 3, 1),
    "span_rcp": (0, 2, 3, 1), "kahan": (12, 0, 0, 2), "subdivided_8": (2 / 8, 0, 3 / 8 + 2, 4 / 8),
}


@pytest.mark.parametrize("name", list(FUSED_OPS))
def test_fma_aware_counts_fuse_each_product_into_its_one_addition(name):
    """On FMA hardware formula (3) is three fused multiply-adds per texel against the incremental form's three
    additions: the same instruction count."""
    ops = M.ops_per_texel(name, fused=True)
    got = tuple(ops.get(kind, (0.0, 0.0))[0] for kind in ("add", "mul", "fma", "div"))
    assert got == pytest.approx(FUSED_OPS[name], abs=1e-9)


def test_a_product_used_twice_is_not_fused():
    ar = Arith(np.float32)
    a = np.ones(4, np.float32)
    product = ar.mul(a, a)
    ar.add(product, a)
    assert dict(ar.fused) == {"mul": 0, "fma": 4}
    ar.add(product, a)  # used again: a multiplication and two additions after all
    assert (ar.fused["mul"], ar.fused["fma"], ar.fused["add"]) == (4, 0, 8)
    both = Arith(np.float32)
    both.add(both.mul(a, a), both.mul(a, a))  # a x + b y: one product fuses, the other stays a multiplication
    assert (both.fused["mul"], both.fused["fma"], both.fused["add"]) == (4, 4, 0)


def test_the_paper_counts_the_shared_denominator_once_per_coordinate():
    """The paper's 8/8/2 (direct) and 4/4/2 (span) are the code's counts plus the denominator's work done a second
    time for v; the code computes q once per texel."""
    for name, q_adds, q_muls in (("direct", 2, 2), ("span", 1, 1), ("incremental", 1, 0)):
        paper = M.METHODS[name].paper_ops
        code = CODE_OPS[name]
        assert (paper[0] - code[0], paper[1] - code[1], paper[2] - code[2]) == (q_adds, q_muls, 0)


def test_mitigations_cost_what_their_counts_say_per_span():
    """Re-anchoring every M pixels adds one multiply per quantity per M pixels."""
    for m in M.REANCHOR_EVERY:
        ops = M.ops_per_texel(f"reanchor_{m}")
        assert ops["mul"][0] == pytest.approx(3 / m)
        assert ops["add"][0] == pytest.approx(3.0)
