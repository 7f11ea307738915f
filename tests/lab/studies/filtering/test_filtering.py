"""The texture-filtering study: its views' geometry, the supersampled reference (pinned to the float64 exact hit,
checked against an analytic supersample of a flat relief, converging with the ray count), the occlusion mask,
the CLI, and the smoke suite end to end (what CI runs)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from wgpuviewer.cli import main
from wgpuviewer.lab.studies.filtering import supersample as ss
from wgpuviewer.lab.studies.filtering.docs import DOCS_BEGIN, DOCS_END, docs_block_of
from wgpuviewer.lab.studies.filtering.pictures import place_labels
from wgpuviewer.lab.studies.filtering.report import rereport
from wgpuviewer.lab.studies.filtering.run import flicker_psnr, flicker_ratio, psnr, psnr_uncertainty, unresolved, void_reason
from wgpuviewer.lab.studies.filtering.suites import (
    EXPLICIT_GRADIENTS,
    SUITES,
    TABLE,
    TUNING_CONFIGS,
    Config,
    resolve_options,
)
from wgpuviewer.lab.studies.filtering.views import (
    ALBEDOS,
    HEIGHT_SCALE,
    MASK_LEVEL,
    TEXTURE_SIZE,
    Case,
    albedo_image,
    depth_map,
    make_view,
    relief_height,
)
from wgpuviewer.relief.filter_probe import explicit_gradient_probe, explicit_gradient_support
from wgpuviewer.relief.filters import DERIVATIVE_LIMIT, FILTERS, FLAGS
from wgpuviewer.relief.reference import exact_hit, uv_error_texels
from wgpuviewer.relief.renderer import Renderer

SIZE = (32, 24)
GOLDEN_SCENE = Path(__file__).resolve().parents[3] / "relief" / "golden" / "scene.toml"  # small textures


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    return tmp_path_factory.mktemp("filtering")


@pytest.fixture(scope="module")
def views(gpu, folder):
    """(view, renderer) per case, made once."""
    cache = {}

    def get(case: Case):
        if case not in cache:
            view = make_view(case, SIZE, folder)
            cache[case] = (view, Renderer(view.scene, gpu))
        return cache[case]

    return get


@pytest.mark.parametrize("angle", [0.0, 45.0, 85.0])
def test_view_has_the_asked_footprint_and_sees_only_the_plane(folder, angle):
    view = make_view(Case("bricks", "checker", angle, 3.0), SIZE, folder)
    uv, v = view.entries(1)
    h, w = SIZE[1], SIZE[0]
    du = np.linalg.norm(uv[h // 2, w // 2 + 1] - uv[h // 2, w // 2]) * TEXTURE_SIZE  # across the view
    assert du == pytest.approx(3.0, rel=0.1)
    theta = np.degrees(np.arccos(v[h // 2, w // 2, 2]))
    assert theta == pytest.approx(angle, abs=1.0)
    assert (v[..., 2] > np.cos(np.radians(89.0))).all()  # every pixel looks at the plane, below the horizon


def test_reference_hits_are_the_float64_exact_hits(views):
    """The reference traces its sub-pixel rays with the renderer's maxmip; the float64 exact hit of the same rays
    (from the view's geometry) agrees."""
    view, renderer = views(Case("bricks", "own", 80.0, 2.0))
    n = 4
    hits, covered = ss.hit_uvs(renderer, view, n)
    uv0, v = view.entries(n)
    ref = exact_hit(depth_map(view), uv0[covered], v[covered], HEIGHT_SCALE)
    assert covered.mean() == 1.0 and ref.valid.all()
    error = uv_error_texels(hits[covered], ref.uv, (TEXTURE_SIZE, TEXTURE_SIZE))
    # float32 rays and hits; a ray grazing an edge may fall on either side of it
    assert np.percentile(error, 99) < 0.02 and (error > 0.5).mean() < 0.002, np.percentile(error, [50, 99, 100])


def test_flat_reference_equals_an_analytic_supersample(views):
    """On the flat relief (depth 1 everywhere) every ray hits at uv0 - (V.xy / V.z) S: computed from the camera
    alone, without renderer, tracer or GPU, the supersample must be the reference's."""
    view, renderer = views(Case("flat0", "photo", 60.0, 2.0))
    reference = ss.supersample(renderer, view, 8)
    analytic = ss.analytic_flat(view, 8, 1.0)
    assert reference.covered.all() and not reference.occluded.any()
    assert np.abs(reference.color - analytic).max() < 2e-3
    assert psnr(reference.color, analytic) > 65.0


@pytest.mark.parametrize("case, tolerance", [
    (Case("flat0", "checker", 60.0, 2.0), 40.0),
    (Case("bricks", "own", 80.0, 2.0), 28.0),
])
def test_reference_converges(views, case, tolerance):
    """8 x 8 rays per pixel are within ``tolerance`` dB PSNR of 16 x 16 (the study reports the value per case), and
    closer than 4 x 4 are."""
    view, renderer = views(case)
    full = ss.supersample(renderer, view, 16)
    p8, p4 = (psnr(ss.supersample(renderer, view, n).color, full.color) for n in (8, 4))
    assert p8 > tolerance and p8 > p4 + 3.0, (p8, p4)


def test_occlusion_mask_marks_pixels_straddling_hidden_texels(views):
    bricks_view, bricks = views(Case("bricks", "own", 80.0, 2.0))
    occluded = ss.supersample(bricks, bricks_view, 8).occluded
    assert 0.05 < occluded.mean() < 0.9
    for angle in (60.0, 85.0):  # at 85 degrees the rays along the view are ~10 times farther apart than across
        flat_view, flat = views(Case("flat0", "checker", angle, 2.0))
        assert not ss.supersample(flat, flat_view, 8).occluded.any(), angle
    # a pair of neighbouring rays 3 texels apart inside one pixel, all other neighbours 0.1 apart: that pixel only
    hits = (np.indices((8, 16)).transpose(1, 2, 0)[..., ::-1] * 0.1).astype(np.float32)  # (x, y) * 0.1 texel
    hits[:, 3:8, 0] += 3.0  # a jump between sub-columns 2 and 3 inside pixel 0 (n = 8); at 7 | 8 it crosses pixels
    mask = ss.occluded_pixels(hits, (1, 1), 8)
    assert mask.tolist() == [[True, False]]


def test_displaced_derivatives_explode_at_depth_discontinuities_and_are_bounded(views):
    """Where neighbouring pixels hit different surfaces the traced uv jumps: the raw displaced derivative is many
    times the unperturbed one there; the source bounds it (flagged). On the flat relief it is the true, modest
    stretch of the deeper plane and nothing is flagged; the analytic source does not jump at the edges."""
    bounded = FLAGS["bounded"]
    view, renderer = views(Case("bricks", "own", 80.0, 2.0))
    stats = {source: renderer.render(Config("ewa", source).draw(), SIZE, view.camera, mode="albedo").filter
             for source in ("displaced", "analytic")}
    ratio = stats["displaced"][..., 3].view(np.float32)
    flags = stats["displaced"][..., 2] >> 24
    assert ratio.max() > 2 * DERIVATIVE_LIMIT and (flags & bounded).any()
    assert ((flags & bounded) > 0)[ratio > DERIVATIVE_LIMIT * 1.01].all()
    analytic = stats["analytic"][..., 3].view(np.float32)
    assert np.median(analytic) < 2.0 and (analytic > DERIVATIVE_LIMIT).mean() < (ratio > DERIVATIVE_LIMIT).mean()
    flat_view, flat = views(Case("flat0", "checker", 60.0, 2.0))
    flat_stats = flat.render(Config("ewa", "displaced").draw(), SIZE, flat_view.camera, mode="albedo").filter
    flat_ratio = flat_stats[..., 3].view(np.float32)
    assert (flat_ratio > 1.0).all() and (flat_ratio < 1.5).all() and not ((flat_stats[..., 2] >> 24) & bounded).any()


def test_gaussian_average_is_a_normalised_symmetric_kernel():
    n = 8
    constant = np.full((3 * n, 4 * n, 3), 0.3)
    covered = np.ones(constant.shape[:2], bool)
    assert np.allclose(ss.gaussian_average(constant, covered, n), 0.3)
    # a linear ramp: the symmetric kernel returns its value at the pixel centres (away from the frame's border)
    x = (np.arange(4 * n) + 0.5) / n
    ramp = np.broadcast_to(x[None, :, None], constant.shape).copy()
    out = ss.gaussian_average(ramp, covered, n)
    assert np.allclose(out[1, 1:3, 0], [1.5, 2.5])


def test_masked_albedo_is_a_fine_checker_exactly_on_the_low_parts():
    for relief in ("bricks", "step", "brick"):
        image = albedo_image("masked", relief=relief)
        low = relief_height(relief) < MASK_LEVEL
        assert 0.05 < low.mean() < 0.95
        grey = image[..., 0]
        # low parts alternate dark and bright from texel to texel; high parts are one colour
        assert np.abs(np.diff(grey, axis=1))[(low[:, 1:] & low[:, :-1])].min() > 0.5
        assert np.ptp(image[~low].reshape(-1, 3), axis=0).max() == 0.0


def test_photographic_relief_is_the_photograph_as_depth_and_own_albedo(folder):
    view = make_view(Case("brick", "own", 80.0, 2.0), (16, 12), folder)
    height = relief_height("brick")
    assert height.shape == (TEXTURE_SIZE, TEXTURE_SIZE) and np.ptp(height) > 0.3
    np.testing.assert_allclose(depth_map(view), 1.0 - height, atol=1e-6)  # brighter = higher = less deep
    assert view.scene.materials["relief"].albedo == view.scene.materials["relief"].height


def test_shifted_view_slides_the_picture_by_the_asked_texels(folder):
    view = make_view(Case("bricks", "checker", 80.0, 2.0), SIZE, folder)
    uv0, v0 = view.entries(1)
    uv1, v1 = view.shifted(0.37).entries(1)
    moved = np.linalg.norm(uv1 - uv0, axis=-1) * TEXTURE_SIZE
    assert np.allclose(moved, 0.37, rtol=1e-6) and np.allclose(v0, v1, atol=1e-12)


def test_explicit_gradient_filters_are_the_ones_whose_wgsl_samples_with_gradients():
    """The void rule's list of filters is the filters' own WGSL: the ones calling textureSampleGrad, with the
    anisotropic kind exactly for a sampler with max_anisotropy."""
    wgsl = Path(__file__).resolve().parents[4] / "wgsl" / "filters"
    calling = {name for name in FILTERS if "textureSampleGrad" in (wgsl / f"{name}.wgsl").read_text()}
    assert calling == set(EXPLICIT_GRADIENTS)
    for name, kind in EXPLICIT_GRADIENTS.items():
        assert (kind == "anisotropic") == any(p.name == "max_anisotropy" for p in FILTERS[name].params)


def test_void_rows_follow_the_gradient_probe(gpu):
    ignored = explicit_gradient_probe(gpu).ignored
    aniso = void_reason(Config("aniso", "analytic", (("max_anisotropy", 16),)), gpu)
    assert bool(aniso) == any("anisotropic" in p for p in ignored)
    trilinear = void_reason(Config("trilinear", "displaced"), gpu)
    assert bool(trilinear) == any("anisotropic" not in p for p in ignored)
    assert void_reason(Config("ewa", "analytic"), gpu) == "" and void_reason(Config("bilinear"), gpu) == ""


def test_flicker_measures_change_against_the_reference_change():
    rng = np.random.default_rng(1)
    reference = rng.uniform(size=(5, 6, 8, 3))
    mask = np.ones((6, 8), bool)
    assert flicker_psnr(reference, reference, mask) == 99.0 and flicker_ratio(reference, reference, mask) == 1.0
    frozen = np.repeat(reference[:1], 5, axis=0)  # a filter that smears all motion away
    assert flicker_ratio(frozen, reference, mask) == 0.0
    shimmer = reference + rng.normal(0, 0.2, reference.shape)  # the true motion plus per-frame noise
    assert flicker_ratio(shimmer, reference, mask) > 1.0 and flicker_psnr(shimmer, reference, mask) < 20.0
    offset = reference + 0.3  # a constant error does not flicker
    assert flicker_psnr(offset, reference, mask) > 90.0


def test_reference_uncertainty_bounds_and_decides_which_differences_are_resolved():
    assert psnr_uncertainty(30.0, 0.0) == 0.0
    # RMS error 10^-1.5; a reference error of the same size can double it: 20 log10(2) dB
    assert psnr_uncertainty(30.0, 10 ** -1.5) == pytest.approx(20 * np.log10(2.0))

    def row(label, value, u):
        return {"label": label, "tracer": "maxmip", "psnr": value, "psnr_uncertainty": u, "void": ""}

    rows = [row("ewa (displaced)", 30.0, 0.2), row("ewa_vis (displaced)", 30.3, 0.2),
            row("ewa (analytic)", 32.0, 0.01), row("trilinear (uv)", 25.0, 0.01), row("bilinear (uv)", 31.95, 0.01)]
    assert unresolved(rows) == [("ewa_vis (displaced)", "ewa (displaced)")]  # 0.3 dB within 0.4; 0.05 is "equal"
    rows[1]["psnr"] = 30.5
    assert unresolved(rows) == []


def test_pareto_labels_do_not_overlap():
    rng = np.random.default_rng(2)
    points = [tuple(p) for p in rng.uniform(0, 100, (30, 2))] + [(50.0, 50.0)] * 5  # a crowd, some on one spot
    widths = list(rng.uniform(40, 120, len(points)))
    offsets = place_labels(points, widths, 8.0, 5.0, marker=3.0)
    boxes = [(px + dx, py + dy - 4, px + dx + w, py + dy + 4) for (px, py), w, (dx, dy) in zip(points, widths, offsets)]
    markers = [(px - 3, py - 3, px + 3, py + 3) for px, py in points]
    for i, a in enumerate(boxes):
        for b in boxes[:i] + markers:
            assert a[2] <= b[0] or a[0] >= b[2] or a[3] <= b[1] or a[1] >= b[3], (a, b)


# --- CLI and the smoke suite ---------------------------------------------------------------------------------


def test_filters_command_lists_every_filter_and_source(capsys):
    assert main(["filters"]) == 0
    out = capsys.readouterr().out
    for name in [*FILTERS, "uv", "displaced", "analytic"]:
        assert name in out


@pytest.mark.parametrize("args, fragments", [
    (["filtering", "--out", "OUT", "--angles", "95"], ["--angles", "95"]),
    (["filtering", "--out", "OUT", "--reliefs", "lava"], ["--reliefs", "lava"]),
    (["filtering", "--out", "OUT", "--filters", "box"], ["--filters", "box"]),
    (["filtering", "--out", "OUT", "--footprints", "x"], ["--footprints"]),
    (["render", "-o", "OUT.png", "--filter", "box"], ["--filter", "box", "ewa_vis"]),
    (["render", "-o", "OUT.png", "--derivatives", "magic"], ["--derivatives", "displaced"]),
])
def test_bad_options_are_one_line_user_errors(tmp_path, capsys, args, fragments):
    args = [a.replace("OUT", str(tmp_path / "out")) for a in args]
    assert main(args) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("wgpuviewer: error:"), lines
    for fragment in fragments:
        assert fragment in lines[0], lines[0]


def test_render_with_a_filter(tmp_path, adapter):
    plain, vis = tmp_path / "trilinear.png", tmp_path / "ewa_vis.png"
    scene = str(GOLDEN_SCENE)
    assert main(["render", scene, "-o", str(plain), "--technique", "maxmip", "--size", "64x36"]) == 0
    assert main(["render", scene, "-o", str(vis), "--technique", "maxmip", "--size", "64x36", "--filter", "ewa_vis",
                 "--derivatives", "displaced"]) == 0
    import cv2

    a, b = cv2.imread(str(plain)).astype(int), cv2.imread(str(vis)).astype(int)
    assert a.shape == b.shape == (36, 64, 3) and 0.1 < np.abs(a - b).mean() < 30


def test_a_stopped_run_keeps_and_reports_the_cases_it_finished(tmp_path, gpu, monkeypatch):
    """Ctrl-C or gpu-suite's SIGTERM during the third case: results.csv holds the first two, report.md says so."""
    from wgpuviewer.lab.studies.filtering import run as run_module

    options = resolve_options("smoke", size=(16, 12), frames=1, filters=["trilinear"])
    calls = []
    measure = run_module.measure_case

    def stopping(*args, **kwargs):
        calls.append(1)
        if len(calls) == 3:
            raise KeyboardInterrupt
        return measure(*args, **kwargs)

    monkeypatch.setattr(run_module, "measure_case", stopping)
    with pytest.raises(KeyboardInterrupt):
        run_module.run(options, tmp_path, progress=False)
    rows = TABLE.read(tmp_path / "results.csv")
    assert [r["case"] for r in rows if r["label"] == "trilinear (uv)"] == [c.name for c in options.suite.cases[:2]]
    assert "**stopped after 2 of 3 cases**" in (tmp_path / "report.md").read_text()


def test_full_suite_measures_the_grazing_middle_footprint_first():
    cases = SUITES["full"].cases
    first = [c for c in cases[:len({(c.relief, c.albedo) for c in cases})]]
    assert {(c.angle, c.footprint) for c in first} == {(80.0, 2.0)}
    assert len(cases) == len(set(cases)) == 3 * 5 * 5 * 3 + 4 * 5 * 3


def test_smoke_suite_end_to_end(tmp_path, gpu):
    out = tmp_path / "smoke"
    assert main(["filtering", "--out", str(out), "--suite", "smoke", "--quiet"]) == 0
    rows = TABLE.read(out / "results.csv")
    assert {"filter", "derivatives", "tracer", "role", "void", "psnr", "ssim", "psnr_gauss", "psnr_occluded",
            "psnr_uncertainty", "time_ratio", "texels_per_pixel", "capped_share", "reference_rays",
            "reference_resolved", "flicker_psnr", "flicker_ratio"} <= set(rows[0])
    labels = {r["label"] for r in rows}
    assert {"trilinear (uv)", "bilinear (uv)", "aniso 16 (uv)", "ewa (displaced)", "ewa_vis (displaced)",
            "ewa_vis_rows (displaced)", "trilinear (uv) [pom32]", "ewa_vis (displaced) [pom32]"} <= labels
    assert "ewa_vis inherit=1 (displaced)" in labels
    probe_honours = explicit_gradient_support(gpu)
    for r in rows:
        assert np.isfinite(r["psnr"]) and 0.0 < r["ssim"] <= 1.0 and r["time_ratio"] > 0 and r["pixels"] > 0
        assert r["psnr_uncertainty"] >= 0.0 and r["reference_rays"] == 16
        if r["label"] in ("trilinear (uv)", "trilinear (uv) [pom32]"):
            assert r["time_ratio"] == 1.0  # each tracer's own baseline
        assert bool(r["void"]) == (r["filter"] == "aniso" and not probe_honours), r
    by = {(r["case"], r["label"]): r for r in rows}
    flat = [c for c, label in by if c.startswith("flat0") and label == "ewa (displaced)"]
    for case in flat:  # nothing is hidden on a flat relief: visibility changes nothing
        assert by[case, "ewa_vis (displaced)"]["psnr"] == by[case, "ewa (displaced)"]["psnr"]
        assert by[case, "ewa_vis (displaced)"]["hidden_per_pixel"] == 0.0
    occluding = [r for r in rows if r["occluding"] is True and r["label"] == "ewa_vis (displaced)" and r["role"] == "rank"]
    assert occluding and all(r["hidden_per_pixel"] > 0 and r["occluded_share"] > 0 for r in occluding)
    # the flicker sweep: the 80-degree cases at x2, every valid configuration; none elsewhere
    swept = [r for r in rows if r["role"] == "rank" and not r["void"] and r["angle"] == 80.0]
    assert swept and all(np.isfinite(r["flicker_psnr"]) and r["flicker_ratio"] > 0 for r in swept)
    assert all(np.isnan(r["flicker_psnr"]) for r in rows if r["angle"] != 80.0 or r["void"] or r["role"] == "tune")
    tune = [r for r in rows if r["role"] == "tune"]
    assert {r["label"] for r in tune} == {c.label for c in TUNING_CONFIGS}
    assert not {r["case"] for r in tune} & {r["case"] for r in rows if r["role"] == "rank"}
    report = (out / "report.md").read_text()
    assert report.startswith("# Texture filtering on relief surfaces (Romanyuk & Dudnyk 2017)\n\n- command: "
                             f"`wgpuviewer filtering --out {out} --suite smoke --quiet`\n- adapter: **{rows[0]['adapter']}**")
    for section in ("## Recommendation", "## Visibility", "## Flicker", "## Tuning", "## Per case"):
        assert section in report, section
    assert "pareto.png" in report and "distributions.png" in report and "crops_" in report
    if not probe_honours:
        assert "**Void rows**" in report and "`aniso 16 (uv)`" in report
    assert (out / "pareto.png").stat().st_size > 10_000 and (out / "distributions.png").stat().st_size > 10_000
    crops = list(out.glob("crops_*.png"))
    assert crops and all(p.stat().st_size > 5_000 for p in crops)
    # the report again from results.csv and run.json, measuring nothing: the same text
    again = tmp_path / "again"
    again.mkdir()
    for crop in crops:
        (again / crop.name).write_bytes(crop.read_bytes())
    assert main(["filtering", "--out", str(again), "--from-csv", str(out / "results.csv"), "--quiet"]) == 0
    assert (again / "report.md").read_text() == report


# --- the committed run: docs and report quote its results.csv -------------------------------------------------

COMMITTED = Path(__file__).resolve().parents[4] / "benchmarks" / "filtering_lavapipe"
DOCS = Path(__file__).resolve().parents[4] / "docs" / "filtering.md"


def test_docs_quote_the_committed_run():
    """docs/filtering.md's generated block is the one its committed results.csv gives, to the character."""
    text = DOCS.read_text()
    start = text.index(DOCS_BEGIN)
    end = text.index(DOCS_END, start) + len(DOCS_END)
    from wgpuviewer.lab import docs
    from wgpuviewer.lab.studies.filtering.docs import BLOCKS

    assert docs_block_of(COMMITTED).split("\n", 1)[1].rstrip(DOCS_END) in text[start:end]  # after any stamp note
    assert text[start:end] == f"{DOCS_BEGIN}\n{docs.body(BLOCKS[0], COMMITTED.parents[1])}\n{DOCS_END}"


def test_committed_report_is_its_results_csv(tmp_path):
    """The committed report.md is what its results.csv and run.json give (nothing edited by hand)."""
    for crop in COMMITTED.glob("crops_*.png"):
        (tmp_path / crop.name).write_bytes(crop.read_bytes())
    rereport(COMMITTED / "results.csv", tmp_path)
    ours = (tmp_path / "report.md").read_text()
    assert ours == (COMMITTED / "report.md").read_text()
    rows = TABLE.read(COMMITTED / "results.csv")
    assert {r["footprint"] for r in rows if r["role"] == "rank"} == {1.0, 2.0, 4.0}
    assert {r["albedo"] for r in rows if r["role"] == "rank"} == set(ALBEDOS)
    assert {r["tracer"] for r in rows} == {"maxmip", "pom32"}
    assert any(r["void"] for r in rows) and any("inherit=1" in r["label"] for r in rows)
    assert any(np.isfinite(r["flicker_psnr"]) for r in rows) and any(r["role"] == "tune" for r in rows)
