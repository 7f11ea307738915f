"""Large height maps on the distance techniques: the volume slots choose the most depth slices and sub-cells (up to
the defaults) that fit the adapter's limits and maptools' (``maptools/volume/slot.py``'s ``volume_plan``), say what
they chose in one warning line, stay exact, and refuse before any work what does not fit even at the fewest slices,
naming what the scene can change. Limits are faked here (a real 1K/2K bake takes minutes on a software adapter:
docs/maps.md has those runs)."""

from __future__ import annotations

import logging

import cv2
import numpy as np
import pytest

from maptools.kinds.distance import slot as distance_slot
from maptools.kinds.distance_refined import cpu as refined_kind
from maptools.kinds.distance_refined import slot as refined_slot
from maptools.volume import cpu as distance_kind
from maptools.volume import slot as volume_slot
from maptools.volume.slot import DISTANCE_SLICES, DISTANCE_SUBCELLS, MIN_SLICES
from tests.relief.scenes import material_scene
from tests.relief.test_resource_limits import no_builtins, one_line, other_gpu  # noqa: F401 - a fixture
from wgpuviewer import cli, textures
from wgpuviewer.core.errors import UserError
from wgpuviewer.relief.accuracy import random_rays
from wgpuviewer.relief.probe import probe
from wgpuviewer.relief.reference import exact_hit, uv_error_texels
from wgpuviewer.relief.renderer import Renderer
from wgpuviewer.scene import parse_scene
from wgpuviewer.textures import builtin_height

VOLUMES = 33  # the refined map's 4 x 8 bins and the plain volume
PLANS = {"distance": distance_slot.plan, "distance_refined": refined_slot.plan}


def volume_plan(gpu, kind: str, w: int, h: int):
    """The plan of the ``kind`` slot."""
    return PLANS[kind](gpu, w, h)
#: WebGPU's default limits: what every adapter offers at least.
WEBGPU_DEFAULTS = {"max-texture-dimension-3d": 2048, "max-buffer-size": 1 << 28,
                   "max-storage-buffer-binding-size": 1 << 27}


def height_scene(technique: str, size: int) -> str:
    return material_scene([technique], f"albedo = 'builtin:bumps'\nheight = {{ builtin = 'bumps', size = [{size}, "
                                       f"{size}] }}")


def test_the_defaults_where_they_fit(gpu):
    for kind in ("distance", "distance_refined"):
        plan = volume_plan(gpu, kind, 256, 256)
        assert (plan.slices, plan.subcells, plan.reduced) == (DISTANCE_SLICES, DISTANCE_SUBCELLS, ())


@pytest.mark.parametrize("size,kind,slices,subcells", [
    (1024, "distance", 16, 4), (1024, "distance_refined", 16, 4),
    (2048, "distance", 16, 2), (2048, "distance_refined", 4, 2)])
def test_1k_and_2k_maps_fit_webgpus_default_limits(gpu, size, kind, slices, subcells):
    """Every adapter offers at least WebGPU's defaults: a 1K and a 2K height map get a map on each."""
    plan = volume_plan(other_gpu(gpu, limits=WEBGPU_DEFAULTS), kind, size, size)
    assert (plan.slices, plan.subcells) == (slices, subcells)
    assert plan.nbytes <= (VOLUMES << 25 if kind == "distance_refined" else 1 << 28)  # 1056 MiB, 256 MiB
    assert bool(plan.advice) == (kind == "distance_refined" and size == 2048)


def test_slices_follow_the_3d_texture_limit(gpu):
    plan = volume_plan(other_gpu(gpu, limits={"max-texture-dimension-3d": 300}), "distance_refined", 64, 64)
    assert (plan.slices, plan.subcells) == (300 // VOLUMES, DISTANCE_SUBCELLS)
    assert plan.reduced == ("9 depth slices instead of 16 (33 x 16 slices stack 528 layers, more than this adapter's "
                            "3D limit of 300 texels)",)
    assert volume_plan(other_gpu(gpu, limits={"max-texture-dimension-3d": 300}), "distance", 64, 64).reduced == ()


def test_slices_follow_maptools_limits(gpu, monkeypatch):
    monkeypatch.setattr(refined_kind, "MAX_VALUES", VOLUMES * 64 * 64 * 6 + 5)
    monkeypatch.setattr(distance_kind, "MAX_VOXELS", 64 * 64 * 7)
    plan = volume_plan(gpu, "distance_refined", 64, 64)
    assert plan.slices == 6
    assert plan.reduced[0] == ("6 depth slices instead of 16 (33 volumes of 64x64x16 hold 2162688 values, more than "
                               f"maptools' limit of {VOLUMES * 64 * 64 * 6 + 5} (float16))")
    plan = volume_plan(gpu, "distance", 64, 64)
    assert plan.slices == 7
    assert plan.reduced[0] == ("7 depth slices instead of 16 (a 64x64x16 volume holds 65536 values, more than "
                               "maptools' limit of 28672 (float32))")


def test_subcells_follow_the_storage_limit(gpu):
    """The bake binds the sub-cell tops whole (K^2 floats a texel): beyond the adapter's storage limit, fewer
    sub-cells (a looser outer solid: still exact, a few more fetches)."""
    limits = {"max-storage-buffer-binding-size": 64 * 64 * 4 * 4 * 4 - 4}  # K = 4's tops, less one float
    plan = volume_plan(other_gpu(gpu, limits=limits), "distance", 64, 64)
    assert (plan.slices, plan.subcells) == (DISTANCE_SLICES, 2)
    assert plan.reduced == ("2x2 sub-cells per cell instead of 4x4 (whose bake needs a 256.0 KiB buffer, more than "
                            "the 256.0 KiB this adapter binds)",)
    assert "2x2 sub-cells per cell" in plan.note("m.distance") and "stays exact" in plan.note("m.distance")


@pytest.mark.parametrize("technique,limits,patch,fix", [
    ("distance_refined", {"max-texture-dimension-3d": VOLUMES * MIN_SLICES - 1}, None,
     r"even at 4 depth slices \(the fewest it is built with\) 33 x 4 slices stack 132 layers, more than this "
     r"adapter's 3D limit of 131 texels; use the technique distance$"),
    ("distance", {}, 48 * 48 * MIN_SLICES - 1,
     r"even at 4 depth slices \(the fewest it is built with\) a 48x48x4 volume holds 9216 values, more than "
     r"maptools' limit of 9215 \(float32\); use a height map of at most 2303 texels \(e.g. 47x47\)$"),
    ("distance", {"max-storage-buffer-binding-size": 48 * 48 * 4 - 4}, None,
     r"baking a 48x48 volume needs storage buffers of 9.0 KiB, more than the 9.0 KiB this adapter binds; use a "
     r"smaller height map$"),
])
def test_what_cannot_fit_is_refused_before_any_work_naming_what_the_scene_can_change(
        gpu, monkeypatch, no_builtins, technique, limits, patch, fix):  # noqa: F811 - the fixture
    if patch is not None:
        monkeypatch.setattr(distance_kind, "MAX_VOXELS", patch)
    s = parse_scene(height_scene(technique, 48))
    with pytest.raises(UserError, match=r"^<scene>: materials.m.height = \{'builtin': 'bumps', 'size': \[48, 48\]\}: "
                                        rf"its {technique} map cannot be built: {technique}: " + fix) as error:
        Renderer(s, other_gpu(gpu, limits=limits)).prepare(technique)
    assert "--" not in str(error.value)


def test_a_reduced_map_is_said_in_one_line_and_renders(gpu, caplog):
    limits = {"max-texture-dimension-3d": VOLUMES * 5, "max-storage-buffer-binding-size": 48 * 48 * 4 * 4}
    renderer = Renderer(parse_scene(height_scene("distance_refined", 48)), other_gpu(gpu, limits=limits))
    with caplog.at_level(logging.WARNING, logger="wgpuviewer"):
        image = renderer.render("distance_refined", (32, 24))
    lines = [r.getMessage() for r in caplog.records if r.name.startswith("wgpuviewer")]
    assert lines == ["m.distance_refined: a 48x48 height map gets 5 depth slices instead of 16 (33 x 16 slices "
                     "stack 528 layers, more than this adapter's 3D limit of 165 texels); 2x2 sub-cells per cell "
                     "instead of 4x4 (whose bake needs a 144.0 KiB buffer, more than the 36.0 KiB this adapter "
                     "binds); 742.5 KiB; the tracer stays exact, at more fetches per ray; the technique distance "
                     "(16 slices here, 72.0 KiB) takes about as many fetches or fewer (docs/maps.md)"], lines
    assert renderer.texture("m", "distance_refined").size == (48, 48, VOLUMES * 5)
    assert image.covered.mean() > 0.2 and np.isfinite(image.data).all()


@pytest.mark.parametrize("technique", ["distance", "distance_refined"])
def test_the_fewest_slices_and_sub_cells_stay_exact(gpu, monkeypatch, technique):
    """A map reduced to MIN_SLICES and 1x1 sub-cells is still safe: the tracer finds the float32-exact first hit
    (as test_techniques.py asks of the defaults), never one behind it."""
    monkeypatch.setattr(volume_slot, "DISTANCE_SLICES", MIN_SLICES)
    monkeypatch.setattr(volume_slot, "DISTANCE_SUBCELLS", 1)
    h = builtin_height("bricks", (40, 48))
    for angle in (0, 45, 80):
        uv, view = random_rays(384, angle, seed=angle)
        got = probe(technique, h, uv, view, 0.05)
        ref = exact_hit(1.0 - h, uv, view, 0.05)
        assert not got.capped.any() and (got.depth <= ref.t + 1e-4).all(), angle
        assert uv_error_texels(got.uv, ref.uv, (48, 40)).max() <= 0.01, angle


def test_a_4k_refined_map_is_refused_from_the_builtins_size_naming_the_2k_that_fits(gpu, no_builtins):  # noqa: F811
    """The QA case: refused from the size alone, before the builtin is generated, naming what a scene can change."""
    s = parse_scene(height_scene("distance_refined", 4096))
    with pytest.raises(UserError, match=r"its distance_refined map cannot be built: distance_refined: even at 4 depth "
                                        r"slices \(the fewest it is built with\) 33 volumes of 4096x4096x4 hold "
                                        r"2214592512 values, more than maptools' limit of 553648128 \(float16\); use "
                                        r"a height map of at most 4194304 texels \(e.g. 2048x2048\), or the "
                                        r"technique distance$"):
        Renderer(s, other_gpu(gpu, limits={"max-texture-dimension-3d": 4096})).prepare("distance_refined")


def test_a_height_file_that_cannot_fit_is_refused_from_its_header_in_one_line(gpu, tmp_path, monkeypatch, capsys):
    """From the file's header, before the file is decoded; the hint is the height map's size, never maptools'
    options, which a scene does not have."""
    cv2.imwrite(str(tmp_path / "h.png"), np.full((800, 1000), 128, np.uint8))
    path = tmp_path / "s.toml"
    path.write_text(material_scene(["distance"], "albedo = [0.5, 0.5, 0.5]\nheight = 'h.png'"))
    monkeypatch.setattr(distance_kind, "MAX_VOXELS", 1000 * 800 * MIN_SLICES - 1)
    textures.clear_cache()
    monkeypatch.setattr(textures, "read_height", lambda *a, **k: pytest.fail("the height file was decoded"))
    assert cli.main(["render", str(path), "-o", str(tmp_path / "x.png"), "--size", "16x16",
                     "--technique", "distance"]) == 2
    line = one_line(capsys)
    assert line == (f"wgpuviewer: error: {path}: materials.m.height = 'h.png': its distance map cannot be built: "
                    "distance: even at 4 depth slices (the fewest it is built with) a 1000x800x4 volume holds 3200000 "
                    "values, more than maptools' limit of 3199999 (float32); use a height map of at most 799999 "
                    "texels (e.g. 999x799)"), line
    assert not (tmp_path / "x.png").exists()
    textures.clear_cache()
