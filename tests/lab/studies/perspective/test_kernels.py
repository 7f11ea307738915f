"""The WGSL kernels against their numpy twins (bit for bit on the software adapter CI uses), the rasteriser's uv
against float64 within the documented tolerance, and the study's GPU timing."""

from __future__ import annotations

import numpy as np
import pytest

from wgpuviewer.core.errors import UserError
from wgpuviewer.lab.studies.perspective import geometry as g
from wgpuviewer.lab.studies.perspective import methods as M
from wgpuviewer.lab.studies.perspective.hardware import hardware_uv, renderer_for
from wgpuviewer.lab.studies.perspective.kernels import PARAMS, SPAN, kernels_for, pack_params, pack_spans
from wgpuviewer.lab.studies.perspective.run import ulp_difference
from wgpuviewer.relief.renderer import Renderer  # noqa: F401 - imports wgpu before the log fixture touches its logger

from .cases import hard_cases

pytestmark = pytest.mark.requires_gpu

#: Vulkan lets hardware round a division to 2.5 ulp and fuse a * b + c; lavapipe does neither (measured: 0 ulp).
HARDWARE_ULP = 4


def _cases():
    yield from hard_cases(7, random_spans=6, grazing_rows=5)
    # spans shorter than parallel_32's threads, more of them than one workgroup holds at 32 threads a span
    tile = g.build(g.Setup(span_length=16, rows=9, tilt=80.0))
    yield "9 spans of 16 pixels", tile, tile.spans


CASES = list(_cases())


@pytest.mark.parametrize("name", [name for name, m in M.METHODS.items() if m.on_gpu])
def test_every_kernel_is_its_numpy_twin(gpu, name):
    kernels = kernels_for(gpu)
    allowed = 0 if gpu.software else HARDWARE_ULP
    precision = M.METHODS[name].precisions[0]
    for label, quad, spans in CASES:
        got = kernels.run(name, quad.coefficients, spans)
        want, _ = M.evaluate(name, precision, quad.coefficients, spans)
        assert np.array_equal(got.flagged, want.flagged), (label, int((got.flagged != want.flagged).sum()))
        assert ulp_difference(got.u, want.u) <= allowed, label
        assert ulp_difference(got.v, want.v) <= allowed, label
        assert np.isfinite(got.u).all() and np.isfinite(got.v).all()


def test_a_method_without_a_kernel_is_refused_by_name(gpu):
    quad = g.build(g.Setup(span_length=4, rows=1, tilt=45.0))
    missing = [name for name, m in M.METHODS.items() if not m.on_gpu]
    assert missing  # the adaptive subdivision is a CPU loop only
    with pytest.raises(ValueError, match=f"{missing[0]} has no GPU kernel"):
        kernels_for(gpu).prepare(missing[0], quad.coefficients, quad.spans)


def test_too_many_spans_for_one_dispatch_is_a_clear_error(gpu):
    quad = g.build(g.Setup(span_length=4, rows=1, tilt=45.0))
    spans = g.Spans(np.zeros(70000, np.int64), np.zeros(70000, np.int64), 4)
    with pytest.raises(UserError, match="workgroups"):
        kernels_for(gpu).prepare("direct", quad.coefficients, spans)


@pytest.mark.parametrize("setup", [
    g.Setup(span_length=640, rows=8, tilt=30.0), g.Setup(span_length=1920, rows=8, tilt=80.0),
    g.Setup(span_length=343, rows=7, tilt=89.9), g.Setup(span_length=1920, rows=4, tilt=80.0, offset=1e6),
    g.Setup(span_length=1, rows=1, tilt=45.0),
])
def test_the_rasterisers_uv_agrees_with_float64_within_the_documented_tolerance(gpu, setup):
    """docs/perspective.md: within 16 float32 spacings of the frame's largest coordinate plus 2 % of the pixel's
    footprint (measured on lavapipe: at most 11 spacings, and 1.5 % of a pixel at 89.9 degrees)."""
    quad = g.build(setup)
    ref = g.reference(quad.coefficients, quad.spans)
    got = hardware_uv(quad, gpu)
    assert not got.flagged.any()  # the quad covers the frame
    err = np.hypot(got.u - ref.u, got.v - ref.v)
    spacing = float(np.spacing(np.float32(max(np.abs(ref.u).max(), np.abs(ref.v).max()))))
    assert (err <= 16 * spacing + 0.02 * ref.footprint).all()


def test_the_rasteriser_is_not_asked_for_an_infinite_quad(gpu):
    with pytest.raises(ValueError, match="horizon"):
        renderer_for(g.build(g.Setup(span_length=64, rows=2, tilt=95.0)), gpu)


def test_the_generated_records_hold_each_methods_inputs_by_field():
    quad = g.build(g.Setup(span_length=8, rows=3, tilt=45.0))
    k = quad.coefficients.astype(np.float32)
    for name in ("direct", "fixed16_16"):
        method = M.METHODS[name]
        params = PARAMS.unpack(pack_params(method, quad.coefficients, quad.spans))[0]
        spans = SPAN.unpack(pack_spans(method, quad.coefficients, quad.spans))
        assert np.array_equal(params["a"], k[:, 0]) and np.array_equal(params["c"], k[:, 2])
        assert (params["span_length"], params["span_count"], params["param"]) == (8, 3, method.param)
        assert np.array_equal(spans["y"], quad.spans.y) and len(spans) == 3
        assert np.array_equal(spans["defined"].T, g.defined_range(quad.coefficients, quad.spans))
        fixed = M.fixed_setup(quad.coefficients, quad.spans) if name == "fixed16_16" else None
        assert np.array_equal(params["fixed_step"], fixed.steps if fixed else np.zeros(3))
        assert np.array_equal(spans["fixed_start"], fixed.starts.T if fixed else np.zeros((3, 3)))
