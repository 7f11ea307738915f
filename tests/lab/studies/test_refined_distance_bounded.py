"""The refined-distance study's bound: the compiled exact hit equals the float64 reference, the exact-visibility map
is safe for the rays it was made from and never below the product's maps (which are safe lower bounds of the exact
value), and the paper's worked example (point C: 3 texels Euclidean, 4 refined, two steps become one)."""

from __future__ import annotations

import numpy as np
import pytest

from maptools.kinds.distance_refined.cpu import distance_refined
from wgpuviewer.lab.studies.refined_distance import bounded, exact, example, reliefs
from wgpuviewer.relief.accuracy import random_rays
from wgpuviewer.relief.reference import exact_hit
from wgpuviewer.textures import builtin_height

pytest.importorskip("numba")

SLICES, SCALE, MAX_ANGLE = 8, 0.1, 85.0


@pytest.mark.parametrize("name", ["bumps", "wall", "noise", "slot"])
def test_compiled_hit_is_the_references(name):
    rng = np.random.default_rng(3)
    height = {"noise": lambda: rng.random((13, 17)), "slot": example.height}.get(
        name, lambda: builtin_height(name, (24, 24)))()
    depth = 1.0 - np.asarray(height, np.float64)
    uv, v = random_rays(3000, 0.0, seed=5)
    v = exact.directions(exact.bins(1, 1, 89.0)[0], 3000, rng)
    ref = exact_hit(depth, uv, v, SCALE).t
    got = exact.first_hits(depth, uv, v, SCALE)
    assert np.allclose(got, ref, rtol=0, atol=1e-12)
    # started part way, before its hit, a ray finds the same hit; started on it, there
    assert np.allclose(exact.first_hits(depth, uv, v, SCALE, t_start=0.5 * ref), ref, atol=1e-12)
    assert np.allclose(exact.first_hits(depth, uv, v, SCALE, t_start=ref), ref, atol=1e-12)


@pytest.fixture(scope="module")
def plate():
    """A 16² plate, its exact-visibility bins (few rays) and the product's maps with the conservative cut."""
    height = reliefs.plate(16)
    raw = exact.raw_bins(height, SLICES, SCALE, 4, 8, MAX_ANGLE, 4, seed=1)
    product = {bins: distance_refined(height, slices=SLICES, height_scale=SCALE, sectors=bins[0], bands=bins[1],
                                      max_angle=MAX_ANGLE, visibility="on", progress=False).astype(np.float64)
               for bins in ((1, 1), (4, 8))}
    return height, raw, product


def test_the_exact_map_holds_for_the_rays_it_was_made_from(plate):
    height, raw, product = plate
    volumes = exact.stored(raw, product[(4, 8)])
    excess = exact.check(height, volumes, SCALE, 4, 8, MAX_ANGLE, 4 * height.size, seed=1)  # the same rays
    assert np.isfinite(raw).any() and np.nanmax(excess) <= 1e-9
    fresh = exact.check(height, volumes, SCALE, 4, 8, MAX_ANGLE, 4 * height.size, seed=2)
    assert (fresh > 1e-3).any()  # so few rays miss some: the check can tell


def test_the_sampled_values_are_never_below_the_products_safe_maps(plate):
    # the product's map with the conservative cut is a lower bound of the exact value, the sampled one lies above it
    _, raw, product = plate
    for r, bins in ((raw, (4, 8)), (exact.single_cone(raw), (1, 1))):
        reached = np.isfinite(r)
        assert reached.mean() > 0.1 and (r[reached] >= product[bins][:-1][reached]).all()
        volumes = exact.stored(r, product[bins])
        assert (volumes[-1] == product[bins][-1]).all() and (volumes[:-1] > product[bins][:-1]).any()


def test_the_papers_worked_example():
    ex = example.solve()
    assert ex.euclidean == pytest.approx(example.EUCLIDEAN, abs=1e-3)
    assert example.REFINED <= ex.refined <= example.REFINED + 0.02  # sampled directions: from above
    assert ex.hit_v1 == pytest.approx(example.REFINED, abs=1e-3)
    assert ex.steepest_visible == pytest.approx(example.rim_angle(), abs=example.POLAR_STEP)
    # Donnelly's loop along V1: with the Euclidean value the first step stops a texel short of A, with the refined
    # one it reaches A (two steps become one)
    assert ex.steps_euclidean[0] == pytest.approx(3.0, abs=1e-3) and len(ex.steps_euclidean) >= 2
    assert ex.hit_v1 - ex.steps_euclidean[0] == pytest.approx(1.0, abs=2e-3)
    assert len(ex.steps_refined) == 1 and ex.steps_refined[0] >= ex.hit_v1 - 1e-3
    # the product's cut is conservative: never steeper-only than the exact horizon
    for n in example.CUT_SECTORS:
        assert example.conservative_cut(n) >= example.rim_angle()


def test_bounded_report_states_the_bound_per_class():
    rows = [{"heightmap": m, "class": c, "angle": a, "variant": v, "fetches_mean": f, "passed": 0.0}
            for m, c in (("grass", "photographs"), ("plate", "perforated")) for a in (45.0, 60.0)
            for v, f in ((bounded.PLAIN, 10.0), (bounded.PAPER, 9.9), (bounded.EXACT_SINGLE, 9.0))]
    classes = bounded.by_class(rows)
    assert set(classes) == {"photographs", "perforated"}
    assert classes["photographs"][bounded.EXACT_SINGLE] == pytest.approx([-0.1, -0.1])
    assert bounded.share(classes["perforated"][bounded.PAPER], classes["perforated"][bounded.EXACT_SINGLE]) == \
        pytest.approx(0.1)


def test_the_bound_alone_writes_its_files_and_report(tmp_path):
    from wgpuviewer.lab.studies.refined_distance.run import SUITES, run

    res = run("smoke", tmp_path, progress=False, command="wgpuviewer refined-distance --only bounded", only="bounded")
    assert not res.rows and {r["heightmap"] for r in res.bounded} == set(SUITES["smoke"].exact_maps)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bounded.csv", "bounded_maps.csv", "example.csv", "report.md",
                                                          "worked_example.png"]
    text = (tmp_path / "report.md").read_text()
    assert "## The paper's worked example" in text and "## The refined map bounded" in text
    assert "## The paper's visibility condition" not in text
