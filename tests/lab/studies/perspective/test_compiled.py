"""The compiled loops (numba) against their numpy twins, bit for bit in float32 and float64, in both builds; what
LLVM made of them; their timing harness; a clear error without numba."""

from __future__ import annotations

import sys

import numpy as np
import pytest

from wgpuviewer.core.errors import UserError
from wgpuviewer.lab.studies.perspective import compiled as C
from wgpuviewer.lab.studies.perspective import geometry as g
from wgpuviewer.lab.studies.perspective import methods as M
from wgpuviewer.lab.studies.perspective.run import instances  # imports wgpu before the log fixture touches its logger

from .cases import hard_cases


def _cases():
    yield from hard_cases(11, random_spans=5, grazing_rows=4)
    frame = g.build(g.Setup(span_length=256, rows=3, tilt=85.0))
    yield "16-pixel tiles", frame, g.tiles_of(frame.frame, 16)


CASES = list(_cases())


def _same(got: M.Result, want: M.Result) -> bool:
    """Equal bits (NaN and signed zeros included) and equal flags."""
    return (got.u.tobytes() == np.ascontiguousarray(want.u).tobytes()
            and got.v.tobytes() == np.ascontiguousarray(want.v).tobytes()
            and np.array_equal(got.flagged, want.flagged))


@pytest.mark.parametrize("name", list(M.METHODS))
def test_every_compiled_loop_is_its_numpy_twin_bit_for_bit(name):
    """Every precision in the scalar build; the timed precision in the SIMD build (vectorising a loop without a
    recurrence changes no IEEE result)."""
    method = M.METHODS[name]
    runs = [(C.build("scalar"), p) for p in method.precisions] + [(C.build("simd"), method.precisions[0])]
    for build, precision in runs:
        for label, quad, spans in CASES:
            want, _ = M.evaluate(name, precision, quad.coefficients, spans)
            got = build.evaluate(name, precision, quad.coefficients, spans)
            assert _same(got, want), (build.name, precision, label)


def test_the_scalar_build_is_scalar_and_the_simd_build_vectorises_the_per_pixel_forms():
    """Read from the optimised LLVM IR: no packed float arithmetic in the scalar build; in the SIMD build the
    per-pixel forms are loop-vectorised, the linear segments vectorised (loop-vectorised on AVX-512 hosts), the float
    running sums are not loop-vectorised (LLVM does not reassociate a float recurrence)."""
    scalar, simd = C.build("scalar"), C.build("simd")
    for name in M.METHODS:
        assert scalar.vectorisation(name) == "scalar", name
    for name in ("direct", "span", "direct_rcp", "span_rcp"):
        assert simd.vectorisation(name).startswith("loop x"), name
    # A linear segment stores at a + m, which numba wraps when negative (a is not known to be >= 0): to LLVM a
    # scatter, which its loop vectoriser takes only where the target has one (AVX-512: "loop x8"); on AVX2 (Haswell,
    # Zen) only the anchors' straight-line code is packed ("slp x2"). Vector code either way, never scalar.
    for name in ("subdivided_16", "adaptive_8"):
        assert simd.vectorisation(name) != "scalar", name
    for name in ("incremental", "two_ended", "kahan", "double_single"):
        assert not simd.vectorisation(name).startswith("loop"), name


def test_a_loop_is_compiled_for_its_signature_only():
    """A call with other argument types is refused, not compiled outside its build's vectoriser setting."""
    quad = g.build(g.Setup(span_length=8, rows=2, tilt=45.0))
    args = C.arguments("direct", quad.coefficients, quad.spans)
    loop = C.build("scalar").loop("direct", np.float32)
    loop(*args.tuple())
    wrong = args.tuple()
    with pytest.raises(TypeError):
        loop(wrong[0].astype(np.float64), *wrong[1:])


def test_timing_gives_per_texel_medians_spreads_and_ratios_to_direct_in_the_same_repeat():
    quad = g.build(instances(g.Setup(span_length=256, rows=8, tilt=80.0), 1)[0])
    names = ["direct", "incremental", "adaptive_8"]
    timing = C.time_loops(C.build("scalar"), names, quad.coefficients, quad.spans, repeats=4, sample_seconds=1e-3)
    assert all(timing.ns[n].shape == (4,) and (timing.ns[n] > 0).all() for n in names)
    assert timing.ratio("direct") == 1.0
    assert all(np.isfinite(timing.spread(n)) and timing.calls[n] >= 1 for n in names)
    expected = float(np.median(timing.ns["incremental"] / timing.ns["direct"]))
    assert timing.ratio("incremental") == expected


def test_the_builds_are_shared_and_unknown_ones_refused():
    assert C.build("simd") is C.build("simd")
    with pytest.raises(ValueError, match="build 'vector'"):
        C.Build("vector")


def test_without_numba_the_study_says_how_to_install_it(monkeypatch):
    monkeypatch.setitem(sys.modules, "numba", None)  # import numba raises ImportError
    with pytest.raises(UserError, match=r"pip install 'wgpuviewer\[bench\]'"):
        C.numba_module()


def test_the_cpu_model_is_named():
    assert C.cpu_model().strip()
