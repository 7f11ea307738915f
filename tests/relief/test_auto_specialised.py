"""auto's modules carry only the methods a material's table picks (``Technique.code_paths`` / ``paths_used``,
``shaders.material_variant``, ``USES_NAME`` constants): the choice follows the table (and, with a screen-space
budget, every level above max_error's), the constants gate the code, the pipeline cache keys on it, and a
specialised module draws exactly what the full one draws."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from wgpuviewer.relief.material_textures import depth_data
from wgpuviewer.relief.renderer import DrawConfig, Renderer
from wgpuviewer.relief.shaders import PLAIN, MaterialVariant, compose_technique, material_variant
from wgpuviewer.scene import load_scene
from wgpuviewer.techniques import TECHNIQUES
from wgpuviewer.techniques.auto import autotable
from wgpuviewer.techniques.auto.autotable import AUTO_BINS, AUTO_BUDGET_LEVELS, AUTO_CANDIDATES, AUTO_METHODS

from .test_render import GOLDEN

AUTO = TECHNIQUES["auto"]


def constants(variant: MaterialVariant) -> dict[str, str]:
    code = compose_technique(AUTO, "probe", variant=variant).code
    return {name: line.rsplit("= ", 1)[1].rstrip(";") for name in AUTO.code_paths
            for line in code.splitlines() if line.startswith(f"const USES_{name.upper()}: bool")}


def test_the_constants_gate_each_method():
    assert AUTO.code_paths == tuple(AUTO_METHODS)
    assert set(constants(PLAIN).values()) == {"true"}
    assert constants(MaterialVariant(paths=("pom", "relief"))) == {
        "basic": "false", "parallax": "false", "pom": "true", "quadmax": "false", "relief": "true"}
    assert "USES_" not in compose_technique(TECHNIQUES["pom"], "probe").code  # a technique without code paths


def test_methods_picked_follow_the_table():
    """A synthetic table: POM 4 meets every budget at small angles, quadmax alone the strictest at the grazing bins,
    relief 32+2 the others there: max_error's level picks quadmax only at the smallest budget; a screen-space budget
    (max_error or more per fragment) takes every level above max_error's."""
    n, angles = len(AUTO_CANDIDATES), AUTO_BINS + 1
    table = np.zeros((n + len(autotable.SCALED), angles, len(autotable.FIELDS)))
    table[..., autotable.FIELDS.index("err_p975")] = 100.0
    table[..., autotable.FIELDS.index("fetches_simd")] = 10.0
    pom4 = AUTO_CANDIDATES.index(("pom", {"layers": 4}))
    relief = AUTO_CANDIDATES.index(("relief", {"linear_steps": 32, "binary_steps": 2}))
    quadmax = AUTO_CANDIDATES.index(("quadmax", {}))
    scaled = n + autotable.SCALED.index(pom4)
    for row in (pom4, scaled):
        table[row, :20, autotable.FIELDS.index("err_p975")] = 0.01
    for row in (relief, n + autotable.SCALED.index(relief)):  # its count at the bins' upper and lower edges
        table[row, 19:, autotable.FIELDS.index("err_p975")] = 0.2
    table[quadmax, :, autotable.FIELDS.index("err_p975")] = 0.0
    assert autotable.methods_picked(table, 0.5, 0.0) == ("pom", "relief")
    assert autotable.methods_picked(table, 0.0625, 0.0) == ("pom", "quadmax")
    assert autotable.methods_picked(table, 0.0625, 0.5) == ("pom", "quadmax", "relief")
    assert AUTO_BUDGET_LEVELS > 1


@pytest.fixture(scope="module")
def scene_renderer(gpu):
    return Renderer(load_scene(GOLDEN / "scene.toml"), gpu)


def test_a_materials_variant_names_its_methods(scene_renderer):
    materials = scene_renderer.scene.materials
    bricks = materials["bricks"]
    variant = material_variant(AUTO, bricks, AUTO.defaults(), "off", False)
    table = autotable.measure(depth_data(bricks), bricks.height_scale)
    assert variant.paths == autotable.methods_picked(table, 0.5, 0.0) and variant.paths
    assert f"+paths={','.join(variant.paths)}" in variant.label
    assert material_variant(TECHNIQUES["pom"], bricks, {"layers": 8}, "hard", True) == \
        MaterialVariant("hard", True, False, None)


def test_a_specialised_module_draws_what_the_full_one_draws(scene_renderer, monkeypatch):
    """The golden scene with auto drawn by each material's specialised module (the renderer's own variant) and by the
    full module (every method compiled in): the same picture and fetches; a module left without the methods the
    table picks draws something else (its pixels flagged), so the constants do gate the code."""
    size = (48, 27)
    got = scene_renderer.render(DrawConfig.of(AUTO), size)
    specialised = {k[-1].paths for k in scene_renderer.pipelines.cache if k[0] == "auto"}
    assert material_variant(AUTO, scene_renderer.scene.materials["bricks"], AUTO.defaults(), "off", False).paths \
        in specialised and None not in specialised

    own = Renderer.variant
    monkeypatch.setattr(Renderer, "variant", lambda self, m, t, d: dataclasses.replace(own(self, m, t, d), paths=None))
    full = scene_renderer.render(DrawConfig.of(AUTO), size)
    assert np.array_equal(got.color, full.color) and np.array_equal(got.data, full.data)
    monkeypatch.setattr(Renderer, "variant", lambda self, m, t, d: MaterialVariant(paths=("basic",)))
    crippled = scene_renderer.render(DrawConfig.of(AUTO), size)
    assert not np.array_equal(crippled.color, full.color)
    assert (crippled.data[..., 3][crippled.covered] < 0).mean() > 0.5  # capped: the table's methods are missing
