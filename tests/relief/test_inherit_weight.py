"""The visibility filters' ``inherit`` weighting: a hidden texel's weight goes to its substitute (the texel its ray
meets) when that lies outside the footprint ellipse. The WGSL (wgsl/common/ewa.wgsl, visibility/traced.wgsl)
against its float64 twin (wgpuviewer.lab.studies.filtering.cpu) through the filter probe, on real and adversarial
footprints; ``inherit`` 0 is the drop convention, unchanged."""

from __future__ import annotations

import numpy as np
import pytest

from tests.relief.test_filters import DEGENERATE, footprints, gpu_and_cpu, near_tolerance, step_case, textures
from wgpuviewer.core.errors import UserError
from wgpuviewer.lab.studies.filtering import cpu
from wgpuviewer.relief.filter_probe import filter_probe
from wgpuviewer.relief.filters import FILTERS, filter_interface, resolve_filter_params
from wgpuviewer.relief.reference import view_dir_from_angles
from wgpuviewer.textures import builtin_height

VISIBILITY = [name for name, f in FILTERS.items() if f.visibility]
INHERIT = {"inherit": 1}
#: A hit this close (level texels) to a cell edge may land in either cell in float32 (the GPU's maxmip hit and its
#: bilinear depth at a coarse texel's centre against the float64 ones). On lavapipe no footprint of these tests
#: differs from its twin through a substitute; the margin is for other adapters' rounding.
EDGE = 2e-3


def test_inherit_is_a_flag_of_the_visibility_filters_only():
    assert VISIBILITY == ["ewa_vis", "ewa_vis_rows"]
    for f in FILTERS.values():
        names = [p.name for p in f.params]
        assert ("inherit" in names) == f.visibility, f.name
        if f.visibility:
            p = f.param("inherit")
            assert (p.default, p.min, p.max, p.kind, p.wgsl_type) == (0, 0, 1, int, "u32")
            assert "    inherit: u32," in filter_interface(f).text
            with pytest.raises(UserError, match="inherit"):
                resolve_filter_params(f, {"inherit": 2})


def _substitute_near_an_edge(depth, filtered: cpu.Filtered, view) -> bool:
    """Whether the ray of one of the twin's hidden texels meets the relief within EDGE of a cell edge of its
    level: the GPU's float32 trace may then name the neighbouring texel as the substitute."""
    h, w = depth.shape
    for level, weights in filtered.weights.items():
        hidden = [t for t, weight in weights.items() if weight == 0.0]
        if not hidden:
            continue
        size = np.array([max(w >> level, 1), max(h >> level, 1)])
        hits = cpu.texel_visibility(depth, (np.array(hidden) + 0.5) / size, view, 0.05).hit * size
        offset = np.abs(hits - np.round(hits))
        if (np.nan_to_num(offset, nan=1.0) < EDGE).any():
            return True
    return False


def _compare(name, texture, uv, dx, dy, view, height):
    """GPU and twin under inherit 1; the footprints whose outcome float32 cannot decide are left out (a margin
    near the visibility tolerance, a substitute hit near a cell edge). Returns the GPU result, the twin's and the
    decided footprints."""
    got, want = gpu_and_cpu(name, texture, uv, dx, dy, view, height, params=INHERIT)
    depth = (1.0 - height).astype(np.float32)
    decided = np.array([not (near_tolerance(depth, w, view) or _substitute_near_an_edge(depth, w, view))
                        for w in want])
    value = np.array([w.value for w in want])
    assert decided.mean() > 0.8, decided.mean()
    assert np.abs(got.value - value).max(axis=1)[decided].max() <= FILTERS[name].twin_tolerance
    for field in ("texels", "hidden", "flags"):
        assert (getattr(got, field)[decided] == np.array([getattr(w, field) for w in want])[decided]).all(), field
    return got, want, decided


@pytest.mark.parametrize("name", VISIBILITY)
@pytest.mark.parametrize("relief", ["bricks", "step", "wall"])
def test_inherit_equals_its_float64_twin(gpu, name, relief):
    """Random footprints (0.05 to 60 texels per pixel, eccentricities to 50, uv outside [0, 1)) on occluding
    reliefs at 60 and 85 degrees: the same texels read (visible ones and substitutes), the same hidden count and
    flags, the same value."""
    texture = textures()["noise 64x48"]
    height = builtin_height(relief, (64, 48))
    inherited = 0
    for angle, azimuth in ((60.0, 20.0), (85.0, 185.0)):
        view = view_dir_from_angles(angle, azimuth)
        uv, dx, dy = footprints(60, (64, 48), seed=int(angle) + 11)
        got, want, decided = _compare(name, texture, uv, dx, dy, view, height)
        inherited += sum(bool(w.substitutes and any(w.substitutes.values())) for w in np.array(want)[decided])
    assert inherited > 10  # substitutes outside the ellipse were found and counted


@pytest.mark.parametrize("name", VISIBILITY)
@pytest.mark.parametrize("angle", [80.0, 85.0])
def test_at_a_grazing_step_the_substitutes_carry_the_hidden_weight(gpu, name, angle):
    """Footprints at real hits on the edge of a step seen from its high side (step_case: level 0, centres below
    column 34, semi-axes of at most 12.2 texels): the hidden texels lie on the low side behind the edge and their
    rays meet the top 18 (80 degrees) or 37 (85 degrees) texels further on. An indicator of the top beyond every
    ellipse's reach (columns 46 to 63) reads exactly 0 when hidden weight is dropped; when it is inherited, it
    reads the share the substitutes there took, wherever the twin put one there, and as much as the twin."""
    height, view, uv, dx, dy = step_case(angle)
    beyond = np.zeros((64, 64, 3), np.float32)
    beyond[:, 46:] = 1.0
    drop = filter_probe(name, beyond, uv, dx, dy, view, height=height)
    assert (drop.value[:, 0] == 0.0).all() and (drop.hidden > 0).mean() > 0.5
    got, want, decided = _compare(name, beyond, uv, dx, dy, view, height)
    there = np.array([any(i % 64 >= 46 for i, _ in w.substitutes.get(0, {})) for w in want])
    assert there.mean() > 0.3
    assert ((got.value[:, 0] > 0.0) == there)[decided].all()
    assert (got.texels > drop.texels)[there].all()  # the substitutes were read


@pytest.mark.parametrize("relief, angles", [("flat0", (0.0, 60.0, 85.0, 89.0)), ("flat1", (0.0, 60.0, 85.0, 89.0)),
                                            ("bricks", (0.0,)), ("wall", (0.0,))])
def test_without_occlusion_inherit_is_drop_exactly(gpu, relief, angles):
    """Flat reliefs at any view, occluding ones seen straight down: nothing is hidden, so both conventions read the
    same texels with the same weights, bit for bit (one shader module: inherit is a uniform)."""
    texture = textures()["bricks albedo"]
    height = builtin_height(relief, (64, 64))
    uv, dx, dy = footprints(200, (64, 64), seed=9)
    for angle in angles:
        view = view_dir_from_angles(angle, 33.0)
        for name in VISIBILITY:
            drop = filter_probe(name, texture, uv, dx, dy, view, height=height)
            inherit = filter_probe(name, texture, uv, dx, dy, view, height=height, filter_params=INHERIT)
            assert (drop.hidden == 0).all() and (drop.depth_fetches > 0).all()
            for field in ("value", "texels", "depth_fetches", "hidden", "flags"):
                assert np.array_equal(getattr(inherit, field), getattr(drop, field)), (relief, angle, name, field)


def test_substitutes_inside_the_ellipse_are_not_counted_again(gpu):
    """A round footprint 9 texels wide per pixel just in front of the step at 30 degrees (read at levels 2 and 3):
    the hidden texels' rays meet the top within the ellipse, whose texels the walk counts with their own weights;
    none is counted again, so inherit equals drop exactly, though texels are hidden."""
    height = builtin_height("step", (64, 64))
    view = view_dir_from_angles(30.0, 0.0)
    uv = np.array([[u, v] for u in (0.46, 0.47, 0.48, 0.49) for v in (0.3, 0.6)])
    dx = np.repeat(np.array([[9.0, 0.0]]) / 64, len(uv), axis=0)
    dy = dx[:, ::-1]
    texture = textures()["noise 64x48"]
    sharp = {"alpha": 6.0}  # the ellipse this case is laid out for (alpha sets its prefilter's size)
    got, want = gpu_and_cpu("ewa_vis", texture, uv, dx, dy, view, height, params={**INHERIT, **sharp})
    drop = filter_probe("ewa_vis", texture, uv, dx, dy, view, height=height, filter_params=sharp)
    assert (got.hidden > 0).all()
    assert all(not any(w.substitutes.values()) for w in want)  # every substitute fell inside
    for field in ("value", "texels", "hidden", "flags"):
        assert np.array_equal(getattr(got, field), getattr(drop, field)), field


@pytest.mark.parametrize("name", VISIBILITY)
def test_degenerate_footprints_stay_finite_and_flagged(gpu, name):
    """Zero, NaN, infinite and huge derivatives, NaN and far uv, under inherit at a normal, a grazing and an
    exactly horizontal view on an occluding relief: finite values within the texture's range, the flags set."""
    texture = textures()["bricks albedo"]
    height = builtin_height("wall", (64, 64))
    uv, dx, dy, want = (np.array([c[k] for c in DEGENERATE.values()]) for k in range(4))
    for view in ((0.0, 0.0, 1.0), view_dir_from_angles(85.0, 10.0), view_dir_from_angles(89.9, 10.0),
                 (1.0, 0.0, 0.0)):
        got = filter_probe(name, texture, uv, dx, dy, view, height=height, filter_params=INHERIT)
        assert np.isfinite(got.value).all(), view
        assert ((got.value >= -1e-6) & (got.value <= 1.0 + 1e-6)).all(), view
        for i, flag in enumerate(want):
            assert got.flags[i] & int(flag) == int(flag), (list(DEGENERATE)[i], got.flags[i])
        assert (got.texels <= FILTERS[name].defaults()["max_texels"]).all()  # a visited texel: itself or its substitute
