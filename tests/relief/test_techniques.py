"""The ray-search techniques pom_adaptive, relief, maxmip, distance and distance_refined, and the registry's view
scales and layer-search ranges: what each one promises, measured with the GPU probe against the float64 reference.
The registry itself: one folder per technique, found without a list, in its order."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from maptools.cache import cached_generate
from maptools.kinds.distance_refined.slot import REFINED_BANDS, REFINED_MAX_ANGLE, REFINED_SECTORS
from maptools.kinds.maxmip.cpu import level_sizes
from maptools.kinds.maxmip.slot import cell_max_height, maxmip_atlas
from tests.relief.scenes import material_scene
from tests.relief.twins import pom_from
from wgpuviewer.core.params import Fixed
from wgpuviewer.relief.accuracy import measure, npot_height, random_rays
from wgpuviewer.relief.maps import DEPTH_RANGE_SLACK, depth_range
from wgpuviewer.relief.output import OUTPUT_MODES, mode_data, mode_picture
from wgpuviewer.relief.probe import probe
from wgpuviewer.relief.reference import exact_hit, uv_error_texels, view_dir_from_angles
from wgpuviewer.relief.renderer import Renderer
from wgpuviewer.relief.shaders import pack_trace_params, trace_params
from wgpuviewer.scene import default_scene_path, load_scene, parse_scene
from wgpuviewer.techniques import TECHNIQUES
from wgpuviewer.techniques.shared import HANDOVER_STEPS, PYRAMID_STEPS
from wgpuviewer.textures import builtin_height

from .batched import probe_batches

REAL = ("bricks", "bumps", "ridges")
HARD = ("flat0", "flat1", "spike", "step", "wall", "checker")
EXACT = ("maxmip", "distance", "distance_refined")  # first hit of the bilinear surface, float32 precision
NEW = (("pom_adaptive", {}), ("pom_adaptive", {"angle_only": True}), ("relief", {}),
       ("maxmip", {}), ("distance", {}), ("distance_refined", {}))
#: Float tolerance for "no hit behind the true first hit", in layer depth t (float32 positions and depths).
T_TOL = 1e-4


def height_map(name: str, size=(64, 64)) -> np.ndarray:
    return builtin_height(name, size)


# --- pom_adaptive: the thesis' layer counts, as the shader uses them ---------------------------------------

def thesis_layers(angle_deg: float, c: float, nmin=4, nmax=32) -> int:
    f = (1.0 - abs(math.cos(math.radians(angle_deg)))) ** 0.8
    nt_min = nmin + (nmax / 2 - nmin) * f
    nt_max = nmin + (nmax - nmin) * f
    return int(nt_min + (nt_max - nt_min) * c)


@pytest.mark.parametrize("angle,f,n_range", [(0, 0.0, (4, 4)), (45, 0.3744, (8, 14)), (80, 0.8585, (14, 28))])
def test_pom_adaptive_reproduces_thesis_table_2_2(gpu, angle, f, n_range):
    """Table 2.2 of the thesis: the layer counts the shader actually uses on a C = 0 map (flat: no gradients)
    and a C = 1 map (checkerboard: gradients everywhere after dilation), for random azimuths."""
    assert round((1 - math.cos(math.radians(angle))) ** 0.8, 4) == f
    uv, view = random_rays(256, angle, seed=2)
    for name, c, expected in (("flat0", 0.0, n_range[0]), ("checker", 1.0, n_range[1])):
        h = height_map(name)
        assert (cached_generate("complexity", h, backend="auto", border="repeat") == round(c * 255)).all()
        got = probe("pom_adaptive", h, uv, view, 0.05)
        assert (got.layers == expected).all(), (name, np.unique(got.layers))
        assert thesis_layers(angle, c) == expected
        assert got.fetches.max() <= expected + 1


def test_pom_adaptive_layers_follow_the_formula_at_every_angle(gpu):
    """N = int(mix(NTmin, NTmax, C)) (truncation) for angles 0-89.9 degrees, C in {0, 1}; values within 1e-3 of
    an integer are skipped (float32 vs float64 may round them either way)."""
    angles = np.linspace(0.0, 89.9, 200)
    uv = np.full((len(angles), 2), 0.4)
    view = view_dir_from_angles(angles, 30.0)
    for name, c in (("flat0", 0.0), ("checker", 1.0)):
        got = probe("pom_adaptive", height_map(name), uv, view, 0.05)
        for a, n in zip(angles, got.layers):
            f = (1.0 - math.cos(math.radians(a))) ** 0.8
            exact = 4 + (16 - 4) * f + ((4 + 28 * f) - (4 + 12 * f)) * c
            if abs(exact - round(exact)) > 1e-3:
                assert n == int(exact), (a, c, n, exact)


def test_pom_adaptive_angle_only_variant(gpu):
    """three.js / Godot: N = int(mix(Nmax, Nmin, |V.z|)), the complexity map ignored."""
    angles = np.array([0.0, 30.0, 45.0, 55.0, 80.0, 89.0])  # none lands on an integer N (60: exactly 20)
    view = view_dir_from_angles(angles, 0.0)
    uv = np.full((len(angles), 2), 0.3)
    for name in ("flat0", "checker"):
        got = probe("pom_adaptive", height_map(name), uv, view, 0.05, angle_only=True, min_layers=8, max_layers=32)
        expected = [int(32 + (8 - 32) * math.cos(math.radians(a))) for a in angles]
        assert list(got.layers) == expected


def test_pom_adaptive_is_pom_with_its_layer_count(gpu):
    """Same search as pom: with Nmin = Nmax = 24 the results equal pom with 24 layers bit for bit."""
    h = height_map("bumps")
    uv, view = random_rays(512, 60, seed=5)
    a = probe("pom_adaptive", h, uv, view, 0.05, min_layers=24, max_layers=24, angle_only=True)
    b = probe("pom", h, uv, view, 0.05, layers=24)
    assert (a.layers == 24).all() and (b.layers == 24).all()
    assert np.array_equal(a.uv, b.uv) and np.array_equal(a.fetches, b.fetches)


# --- relief ------------------------------------------------------------------------------------------------

def test_relief_binary_steps_shrink_the_error(gpu):
    """The secant finish (common/binary.wgsl) is second order: each halving of the bracket cuts the p95 about
    fourfold (a midpoint finish: twofold) down to float32's floor, and the hit stays within the final bracket, one
    linear step / 2^binary_steps. The finish against the midpoint: tests/relief/test_relief_finish.py."""
    h = height_map("bumps", (128, 128))
    steps = (0, 1, 2, 4)
    errors = [measure("relief", h, 60, rays=1024, linear_steps=4, binary_steps=b).error_p95 for b in steps]
    assert all(a > 2.5 * b > 0 for a, b in zip(errors, errors[1:])), errors
    step_texels = math.tan(math.radians(60)) * 0.05 * 128 / 4
    assert all(e <= step_texels / 2**b for e, b in zip(errors, steps)), errors


def test_relief_without_binary_steps_is_pom(gpu):
    """The secant through the bracket of the linear search is POM's interpolation (to float32 rounding)."""
    h = height_map("ridges")
    uv, view = random_rays(512, 50, seed=4)
    a = probe("relief", h, uv, view, 0.05, linear_steps=16, binary_steps=0)
    b = probe("pom", h, uv, view, 0.05, layers=16)
    assert np.allclose(a.uv, b.uv, atol=1e-5) and np.array_equal(a.fetches, b.fetches)


@pytest.mark.parametrize("linear,binary", [(1, 0), (8, 3), (16, 6), (64, 10)])
def test_relief_fetch_bound(gpu, linear, binary):
    uv, view = random_rays(512, 70)
    got = probe("relief", height_map("checker"), uv, view, 0.05, linear_steps=linear, binary_steps=binary)
    assert got.fetches.min() >= 1 and got.fetches.max() <= linear + 1 + binary
    assert (got.layers == linear).all()


# --- exact tracers: maxmip, distance, distance_refined -------------------------------------------------------

@pytest.mark.parametrize("technique", EXACT)
@pytest.mark.parametrize("name", REAL + HARD)
def test_exact_tracers_find_the_first_hit(gpu, technique, name):
    """Float32-exact first hit at 0-85 degrees: on the reference surface to a small fraction of a texel (that it is
    never behind the first hit is a contract of every exact tracer: test_contracts.py)."""
    h = height_map(name)
    ref_depth = 1.0 - h
    angles = (0, 60, 80, 85)
    batches = [random_rays(512, angle, seed=angle) for angle in angles]
    for angle, (uv, view), got in zip(angles, batches, probe_batches(technique, h, batches, 0.05)):
        ref = exact_hit(ref_depth, uv, view, 0.05)
        ok = ~got.capped
        assert ok.mean() >= 0.99, (angle, ok.mean())
        err = uv_error_texels(got.uv[ok], ref.uv[ok], (64, 64))
        assert np.percentile(err, 99) <= 0.01 and err.max() <= 0.5, (angle, float(err.max()))


@pytest.mark.parametrize("technique", EXACT)
def test_exact_tracers_on_npot_and_single_texel_maps(gpu, technique):
    h = npot_height()
    if technique == "distance_refined":  # still NPOT and non-square; the full map's 33-volume bake is 90 s on lavapipe
        h = h[:131, :97]
    uv, view = random_rays(1024, 70, seed=9)
    got = probe(technique, h, uv, view, 0.05)
    ref = exact_hit(1.0 - h, uv, view, 0.05)
    assert not got.capped.any()
    assert (got.depth <= ref.t + T_TOL).all()
    assert uv_error_texels(got.uv, ref.uv, (h.shape[1], h.shape[0])).max() <= 0.01
    one = probe(technique, np.full((1, 1), 0.25), uv, view, 0.1)
    assert np.allclose(one.depth, 0.75, atol=1e-5) and not one.capped.any()


@pytest.mark.parametrize("technique", EXACT)
def test_exact_tracers_at_89_degrees(gpu, technique):
    """Very grazing rays walk many cells: the cap may stop some (flagged), but none passes a surface."""
    h = height_map("wall")
    uv, view = random_rays(512, 89.0, seed=1)
    got = probe(technique, h, uv, view, 0.05)
    ref = exact_hit(1.0 - h, uv, view, 0.05)
    assert (got.depth <= ref.t + T_TOL).all()  # capped rays stop short, never behind
    ok = ~got.capped
    assert ok.mean() > 0.5
    assert uv_error_texels(got.uv[ok], ref.uv[ok], (64, 64)).max() <= 0.05


def test_capped_rays_stop_short_and_are_flagged(gpu):
    h = height_map("bumps")
    uv, view = random_rays(512, 80, seed=3)
    ref = exact_hit(1.0 - h, uv, view, 0.05)
    for technique, params in (("maxmip", {"max_steps": 3}), ("distance", {"iterations": 2})):
        got = probe(technique, h, uv, view, 0.05, **params)
        assert got.capped.mean() > 0.5
        assert (got.depth <= ref.t + T_TOL).all()


def test_maxmip_pyramid_bounds_every_cell_it_covers():
    """Node i of level m bounds the cells [i 2^m, (i+1) 2^m) (ceil-halving levels, odd sizes included), and the
    atlas rows are where common/maxmip_walk.wgsl looks for them."""
    rng = np.random.default_rng(0)
    depth = rng.random((13, 7))
    cells = cell_max_height(depth)
    h = 1.0 - depth
    brute = np.max([np.roll(h, (-dy, -dx), axis=(0, 1)) for dy in (0, 1) for dx in (0, 1)], axis=0)
    assert np.array_equal(cells, brute.astype(np.float32))
    levels = cached_generate("maxmip", cells, backend="cpu")
    assert [lv.shape for lv in levels] == level_sizes(13, 7)
    for m, level in enumerate(levels):
        for j in range(level.shape[0]):
            for i in range(level.shape[1]):
                block = cells[j << m:(j + 1) << m, i << m:(i + 1) << m]
                assert level[j, i] >= block.max()
    atlas = maxmip_atlas(levels)
    row = 0
    for level in levels:
        assert np.array_equal(atlas[row:row + level.shape[0], :level.shape[1]], level)
        row += level.shape[0]


def test_distance_refined_uses_the_same_tracer():
    """One tracer, two textures: the plain map is one volume every ray reads; the refined map's bins and the plain
    volume after them, described by the fixed TraceParams the tracer picks a ray's volume with."""
    plain, refined = TECHNIQUES["distance"], TECHNIQUES["distance_refined"]
    assert plain.wgsl_file == refined.wgsl_file == str(Path(plain.folder) / "distance.wgsl")
    assert plain.params == refined.params
    p, r = plain.fixed_values(), refined.fixed_values()
    finish = {"handover_steps": HANDOVER_STEPS, "pyramid_steps": PYRAMID_STEPS}  # the grazing finish
    assert p == {"sectors": 1, "bands": 1, "steep_cos": -2, "volumes": 1, **finish}
    assert r == {"sectors": REFINED_SECTORS, "bands": REFINED_BANDS, "volumes": REFINED_SECTORS * REFINED_BANDS + 1,
                 "steep_cos": pytest.approx(math.cos(math.radians(REFINED_MAX_ANGLE))), **finish}
    for t in (plain, refined):
        assert "maxmip" in t.textures and t.fetch_bound({"iterations": 10}) == 20 + PYRAMID_STEPS


def test_distance_refined_fetches_against_plain(gpu):
    """Both exact; the refined map takes fewer fetches inside its cone, the more the steeper, and beyond it the plain
    volume's (stored as float16, rounded down: a hair shorter steps). Both start at the map's shallowest depth, which
    saves the plain map's short steps above the relief more than the refined map's long ones."""
    h = height_map("bricks")
    for angle, most in ((30, 0.995), (60, 0.96), (80, 0.86), (87, 1.01)):
        plain = measure("distance", h, angle, rays=1024)
        refined = measure("distance_refined", h, angle, rays=1024)
        assert plain.error_p95 <= 0.01 and refined.error_p95 <= 0.01
        assert refined.fetches_mean <= plain.fetches_mean * most, (angle, refined, plain)
    assert refined.fetches_mean >= plain.fetches_mean * 0.99


# --- rendering ----------------------------------------------------------------------------------------------

@pytest.fixture(scope="module")
def scene_renderer(gpu):
    return Renderer(load_scene(default_scene_path()), gpu)


def test_layers_mode_shows_the_adaptive_layer_count(scene_renderer):
    assert "layers" in OUTPUT_MODES
    image = scene_renderer.render("pom_adaptive", (128, 72))
    layers = mode_data(image, "layers")
    drawn = layers[image.covered]
    assert drawn.min() >= 4 and drawn.max() <= 32 and len(np.unique(drawn)) > 3
    assert np.isnan(layers[~image.covered]).all()
    grey = mode_picture(image, "layers")
    expected = np.rint(np.clip((drawn - 4) / 28, 0, 1) * 255)
    assert np.array_equal(grey[image.covered][:, 0], expected.astype(np.uint8))
    fixed = mode_data(scene_renderer.render("relief", (64, 36)), "layers")
    assert set(np.unique(fixed[np.isfinite(fixed)])) == {16.0}


def test_cost_scale_bounds_each_search():
    """The cost view's full heat: the fetch bound of layer searches, a common scale otherwise."""
    from wgpuviewer.techniques import COMMON_COST_SCALE, TECHNIQUES

    assert TECHNIQUES["pom"].cost_scale({"layers": 32}) == 33
    assert TECHNIQUES["pom_adaptive"].cost_scale(TECHNIQUES["pom_adaptive"].defaults()) == 33
    assert TECHNIQUES["relief"].cost_scale({"linear_steps": 16, "binary_steps": 6}) == 23
    assert TECHNIQUES["maxmip"].cost_scale(TECHNIQUES["maxmip"].defaults()) == COMMON_COST_SCALE


def _cost_scale_by_parameter_names(params: dict) -> float:
    """The cost view's scale as it was once inferred from parameter names (frozen: the entries keep its values)."""
    from wgpuviewer.techniques import COMMON_COST_SCALE

    if "layers" in params:
        return float(params["layers"] + 1)
    if "max_layers" in params:
        return float(params["max_layers"] + 1)
    if "linear_steps" in params:
        # contact's second search: its sub-step at the bracket's solid end is the march's own sample
        return float(params["linear_steps"] + 1 + params.get("binary_steps", 0) + params.get("refine_steps", 1) - 1)
    return COMMON_COST_SCALE


def _layer_range_by_parameter_names(params: dict) -> tuple[float, float]:
    """The layers view's range as it was once inferred from parameter names (frozen, as above)."""
    from wgpuviewer.techniques.auto.autotable import AUTO_CANDIDATES

    if "max_error" in params:
        return 1.0, float(len(AUTO_CANDIDATES))
    if params.get("max_layers", 0) > 0:
        return float(params.get("min_layers", 0)), float(params["max_layers"])
    return 0.0, float(max(params.get("layers", 0), params.get("linear_steps", 0), 1))


def test_cost_and_layer_views_keep_their_scales():
    """Each entry's own cost_scale and layer_range give what the parameter names once gave, for its defaults,
    contract parameters and accuracy settings."""
    from wgpuviewer.core.params import resolve_params

    for t in TECHNIQUES.values():
        for overrides in ({}, *t.contract_params, *t.accuracy_settings):
            params = resolve_params(t, overrides)
            assert t.cost_scale(params) == _cost_scale_by_parameter_names(params), (t.name, overrides)
            assert t.layer_range(params) == _layer_range_by_parameter_names(params), (t.name, overrides)


# --- layer searches march the depth map's range --------------------------------------------------------------

def test_depth_range_is_the_uploaded_maps_range_widened():
    d = np.array([[0.3, 0.45], [0.6, 0.5]])
    lo, hi = depth_range(d, "r32float")
    assert lo == pytest.approx(0.3 - DEPTH_RANGE_SLACK, abs=1e-7) and hi == pytest.approx(0.6 + DEPTH_RANGE_SLACK, abs=1e-7)
    lo16, hi16 = depth_range(d, "r16float")  # as a float16 texture holds it
    assert lo16 == float(np.float16(0.3)) - DEPTH_RANGE_SLACK and hi16 == float(np.float16(0.6)) + DEPTH_RANGE_SLACK
    assert depth_range(np.array([[0.0, 1.0]]), "r32float") == (0.0, 1.0)  # kept in [0, 1]
    assert depth_range(np.ones((2, 2)), "r16float") == (1.0 - DEPTH_RANGE_SLACK, 1.0)


LAYER_SEARCHES = (("steep", {"layers": 16}), ("pom", {"layers": 16}), ("pom_adaptive", {}),
                  ("relief", {"linear_steps": 16, "binary_steps": 0}), ("auto", {}))


@pytest.mark.parametrize("technique,params", LAYER_SEARCHES)
def test_layer_searches_stay_in_the_maps_depth_range(gpu, technique, params):
    h = 0.35 + 0.3 * height_map("bumps")  # depths within [0.35, 0.65]
    lo, hi = depth_range(1.0 - h, gpu.depth_format)
    for angle in (30, 60, 85):
        uv, view = random_rays(1024, angle, seed=angle)
        got = probe(technique, h, uv, view, 0.05, **params)
        assert (got.depth >= lo - 1e-6).all() and (got.depth <= hi + 1e-6).all()


def test_pom_marches_the_range_as_its_float64_twin(gpu):
    h = 0.35 + 0.3 * height_map("bumps")
    uv, view = random_rays(1024, 70, seed=2)
    got = probe("pom", h, uv, view, 0.05, layers=8)
    want = pom_from(h, uv, view, 0.05, np.zeros(len(uv)), 8, depth_range(1.0 - h, gpu.depth_format))
    close = np.abs(got.depth - want) <= 1e-3
    assert close.mean() >= 0.97, close.mean()  # hardware bilinear vs float64 may flip a layer test on a few rays


def test_a_map_of_half_the_range_costs_pom_what_half_the_scale_does(gpu):
    """The layers go where the relief is: a map squeezed into half the depth range at scale S is the same relief as
    the full map at scale S / 2 below a free layer, so POM's error and layer count match those (before the range,
    half of the layers were spent where no surface can be)."""
    h = height_map("bumps")
    squeezed = 0.25 + 0.5 * h
    full = measure("pom", h, 70, rays=2048, height_scale=0.025, layers=8)
    half = measure("pom", squeezed, 70, rays=2048, height_scale=0.05, layers=8)
    assert half.error_p95 <= 1.15 * full.error_p95 + 0.01, (half.error_p95, full.error_p95)
    assert abs(half.fetches_mean - full.fetches_mean) <= 0.1 * full.fetches_mean + 0.5


@pytest.mark.parametrize("name", ["flat0", "flat1"])
@pytest.mark.parametrize("technique", ["steep", "pom", "relief"])
def test_a_flat_maps_range_is_the_slack_alone_and_still_hits(gpu, name, technique):
    """Edge case: a flat map's range is 2 DEPTH_RANGE_SLACK wide at most (at the floor, only the slack above it)."""
    h = height_map(name)
    uv, view = random_rays(512, 80, seed=1)
    got = probe(technique, h, uv, view, 0.05)
    ref = exact_hit(1.0 - h, uv, view, 0.05)
    assert np.isfinite(got.uv).all() and not got.capped.any()
    assert uv_error_texels(got.uv, ref.uv, h.shape[::-1]).max() <= 0.05


def test_the_renderer_marches_the_materials_range(gpu, tmp_path):
    """Drawn, not only probed: steep's hit depths sit on its layer grid over the material's depth range."""
    height = 0.35 + 0.3 * height_map("bumps")  # depths within [0.35, 0.65]: a range of 0.3 at most
    Image.fromarray(np.round(height * 65535).astype(np.uint16)).save(tmp_path / "h.png")
    scene_path = tmp_path / "scene.toml"
    scene_path.write_text(material_scene(["steep"], 'albedo = [0.8, 0.8, 0.8]\nheight = "h.png"\nheight_scale = 0.05',
                                         position=(0.3, 0.8, 1.2)))
    renderer = Renderer(parse_scene(scene_path.read_text(), scene_path), gpu)
    image = renderer.render(renderer.config("steep", {"layers": 8}), (48, 32))
    depth = mode_data(image, "layer_depth")[image.covered]
    lo, hi = renderer.depth_range("m")
    assert np.allclose((lo, hi), depth_range(1.0 - height, gpu.depth_format), atol=1e-4)  # (16-bit PNG)
    k = (depth - lo) / ((hi - lo) / 8)
    assert depth.size > 500 and np.abs(k - np.round(k)).max() < 1e-3 and k.min() > -1e-3


def test_trace_params_fields_have_their_declared_types():
    """TraceParams holds every value in its own WGSL type, from the declarations: an integer parameter u32 (i32 where
    its range goes below 0), a flag u32, a number f32; fixed values as declared; the depth map's size u32."""
    types = {name: dict(t.trace_field_types) for name, t in TECHNIQUES.items()}
    for t in types.values():
        assert {k: t[k] for k in ("height_scale", "depth_width", "depth_height", "depth_min", "depth_max")} == {
            "height_scale": "f32", "depth_width": "u32", "depth_height": "u32", "depth_min": "f32", "depth_max": "f32"}
    assert types["pom"]["layers"] == types["relief"]["binary_steps"] == types["parallax"]["offset_limiting"] == "u32"
    assert types["quadmax"]["top_offset"] == types["quadmax_pom"]["top_offset"] == "i32"
    assert types["auto"]["max_error"] == "f32" and types["auto"]["budget_log2_min"] == "i32"
    assert types["cone"]["max_ratio"] == "f32" and types["cone"]["halvings_max"] == types["distance"]["volumes"] == "u32"
    assert "    top_offset: i32,\n    max_steps: u32,\n" in trace_params(TECHNIQUES["quadmax"]).wgsl()
    # packed in those types: integers as integers, not as a float's bits
    record = trace_params(TECHNIQUES["quadmax"]).unpack(
        pack_trace_params(TECHNIQUES["quadmax"], 0.25, (8, 16), {"top_offset": -3, "max_steps": 7}, (0.125, 0.75)))[0]
    assert (record["top_offset"], record["max_steps"], record["depth_width"], record["depth_height"]) == (-3, 7, 16, 8)
    assert (record["height_scale"], record["depth_min"], record["depth_max"]) == (0.25, 0.125, 0.75)
    flags = trace_params(TECHNIQUES["pom_adaptive"]).unpack(
        pack_trace_params(TECHNIQUES["pom_adaptive"], 0.1, (4, 4), {"angle_only": True}))[0]
    assert (flags["angle_only"], flags["min_layers"], flags["max_layers"]) == (1, 4, 32)
    for value, wgsl_type in ((2.5, "u32"), (-1, "u32"), (1.0, "i32"), (1, "vec2f")):
        with pytest.raises(ValueError, match="fixed value 'n'"):
            Fixed("n", value, wgsl_type)


def test_markdown_table_has_a_row_per_technique():
    """The README's technique table, generated from the registry: one row per entry, in registry order."""
    from wgpuviewer.techniques import markdown_table

    header, rule, *rows = markdown_table().split("\n")
    assert header == "| key | name | needs | what it costs (fetches per ray) | parameters |" and rule == "|---|---|---|---|---|"
    assert len(rows) == len(TECHNIQUES)
    for row, t in zip(rows, TECHNIQUES.values(), strict=True):
        key, name, needs, cost, params = (cell.strip() for cell in row.strip("|").split(" | "))
        assert key == t.key and name.startswith(f"`{t.name}`") and ("(exact)" in name) == t.exact
        assert needs == ", ".join(t.textures) and cost == t.cost
        assert [c.split("`")[1] for c in params.split(", ")] == [p.name for p in t.params] if t.params else params == "—"
    assert "`layers` 16 (1 to 1024)" in rows[list(TECHNIQUES).index("pom")]
    assert "`offset_limiting` (off)" in rows[list(TECHNIQUES).index("parallax")]


# --- the registry: one folder per technique, found without a list ------------------------------------------

#: The registry's order (the viewer's keys, the README table, the benchmark's rows).
ORDER = ("basic", "normal", "parallax", "steep", "pom", "pom_adaptive", "relief", "contact", "maxmip", "distance",
         "distance_refined", "quadmax", "quadmax_pom", "auto", "cone")


def test_every_technique_is_its_folder_in_order():
    """Each entry comes from wgpuviewer/techniques/NAME/ (its TECHNIQUE, its folder filled in), its WGSL file is in
    its folder (distance_refined's is distance's), and the registry is read-only."""
    import wgpuviewer.techniques as registry

    assert tuple(TECHNIQUES) == ORDER
    package = Path(registry.__file__).parent
    folders = sorted(p.name for p in package.iterdir() if (p / "__init__.py").is_file())
    assert folders == sorted(ORDER)
    for name, t in TECHNIQUES.items():
        assert t.folder == str(package / name) and Path(t.wgsl_file).is_file()
        assert Path(t.wgsl_file).parent == (package / ("distance" if name == "distance_refined" else name))
    with pytest.raises(TypeError):
        TECHNIQUES["pom"] = TECHNIQUES["steep"]
