"""The refined-distance study's blocks on docs/maps.md compute what they say from its CSVs: synthetic results with
known changes, written as the study writes them."""

from __future__ import annotations

from pathlib import Path

import pytest

from wgpuviewer.lab.studies.refined_distance import docs, pits
from wgpuviewer.lab.studies.refined_distance.run import COSTS_TABLE, DONNELLY_TABLE, FORMATS_TABLE, TABLE

ANGLES = (45.0, 60.0, 75.0, 80.0)
#: Fetches of each variant over `distance`'s (10 per pixel), per map: the answers the blocks must find.
CHANGE = {
    docs.BASELINE: {"bricks": 0.25, "grille": 0.25},
    "plain K=1": {"bricks": 0.05, "grille": 0.08},
    "single cone": {"bricks": -0.0004, "grille": -0.0004},
    "single cone, visibility on": {"bricks": -0.0004, "grille": -0.0024},
    "8 sectors x 1 bands": {"bricks": -0.10, "grille": -0.40},
    "1 sectors x 8 bands": {"bricks": -0.20, "grille": -0.05},
    "2 sectors x 8 bands": {"bricks": -0.25, "grille": -0.25},
    docs.REFINED: {"bricks": -0.30, "grille": -0.30},
    "4 sectors x 8 bands, visibility on": {"bricks": -0.30, "grille": -0.30},
    "plain K=4, 8-bit": {"bricks": 0.02, "grille": 0.01},
}


def result(name, angle, variant, mean, simd=None, tracer=docs.TWIN, capped=0.0):
    return {"heightmap": name, "size": "64x64", "angle": angle, "variant": variant, "tracer": tracer,
            "fetches_mean": mean, "fetches_simd": mean if simd is None else simd, "capped": capped, "build_s": 1.0,
            "memory_mib": 1.0}


@pytest.fixture
def root(tmp_path) -> Path:
    run = tmp_path / docs.RUN
    run.mkdir(parents=True)
    rows = []
    for name in ("bricks", "grille"):
        for angle in ANGLES:
            rows.append(result(name, angle, docs.DISTANCE, 10.0))
            rows.append(result(name, angle, "plain K=4, float32", 10.0 / 1.001))
            for variant, change in CHANGE.items():
                simd = 10.0 * 1.03 if variant == "plain K=4, 8-bit" else None
                rows.append(result(name, angle, variant, 10.0 * (1.0 + change[name]), simd))
    rows.append(result("bricks", 45.0, docs.DISTANCE, 10.0 * 1.00002, tracer="GPU (test)"))
    rows.append(result("bricks", 80.0, docs.DISTANCE, 11.0, tracer="GPU (test)"))
    rows[0]["capped"] = 0.002  # bricks 45°, `distance`
    TABLE.write(run / "results.csv", rows)
    donnelly = [{"heightmap": name, "size": "64x64", "angle": 60.0, "variant": variant, "regime": "fixed",
                 "iterations": 16, "fetches_mean": 16.0, "error_p95": p95, "error_max": p95, "passed": 0.0,
                 "rays": 64} for name, variant, p95 in (("bricks", docs.DISTANCE, 1.0),
                                                         ("bricks", "plain K=4, 8-bit", 1.5),
                                                         ("grille", docs.DISTANCE, 0.5),
                                                         ("grille", "plain K=4, 8-bit", 0.6))]
    DONNELLY_TABLE.write(run / "donnelly.csv", donnelly)
    plates = []
    for angle, on, holes, p95 in ((15.0, 9.5, 9.0, 1.2), (45.0, 9.9, 9.8, 1.0)):
        for bins in ("1 x 1", "4 x 8"):
            for visibility, mean, hole, error in (("off", 10.0, 10.0, 1.0), ("on", on, holes, p95)):
                plates.append({"plate": "holes 16", "size": 32, "hole_depth": 25.6, "angle": angle, "bins": bins,
                               "visibility": visibility, "fetches_mean": mean, "fetches_holes": hole, "budget": 8,
                               "error_p95_holes": error, "rays": 100})
    pits.TABLE.write(run / "pits.csv", plates)
    FORMATS_TABLE.write(run / "formats.csv", [
        {"format": "distance", "size": 64, "backend": backend, "build_s": s, "extrapolated": backend == "cpu",
         "bytes_per_texel": 32.0, "settings": "16 slices"} for backend, s in (("gpu", 0.5), ("cpu", 2.0))])
    COSTS_TABLE.write(run / "format_costs.csv", [
        {"heightmap": "bricks", "size": "64x64", "format": "distance", "angle": 45.0, "fetches_mean": 6.0,
         "fetches_simd": 9.0, "capped": 0.0, "ms": 3.5}])
    return tmp_path


def test_cost_table_changes_gpu_agreement_and_capped_pixels(root):
    text = docs.cost_body(root)
    line = next(x for x in text.splitlines() if x.startswith("| bricks | 45° |"))
    cells = [c.strip() for c in line.strip("|").split("|")]
    assert cells[2:4] == ["12.50 / 12.50", "10.00 / 10.00"]
    assert cells[-3:] == ["-20 % / -20 %", "-44 % / -44 %", "-30 % / -30 %"]
    assert "at 0-60° differ from the twin's by at most 0.002 % (1 rows)" in text
    assert "from 75° on differ from the twin's by at most 10 % (1 rows)" in text
    assert "Pixels the twin capped: plain K=4 on bricks at 45° 0.2 %." in text


def test_result_gives_the_condition_and_the_bins_over_maps_and_angles(root):
    text = docs.result_body(root)
    assert "single cone changes its mean fetches by -0.20 to +0.00 %" in text
    assert "the single cone without it is within -0.04 % of `distance`" in text
    assert "on the binned map the condition changes +0.00 %" in text
    assert "`distance_refined` against `distance`: -30 % at 45°" in text
    assert "against the baseline: -44 % at 45°" in text
    assert "`distance` against the baseline: -20 % at 45°, -20 % at 75-80°" in text


def test_ablation_compares_the_layouts(root):
    text = docs.ablation_body(root)
    assert "| grille | 60° | +8 % | -40 % | -5 % | -25 % | -30 % |" in text
    assert "one sub-cell (K = 1) costs +5 to +8 % against `distance`" in text
    assert "4 x 8 bins take 20 to 20 points fewer than 8 x 1 on the builtins (bricks)" in text
    assert "5 to 5 points fewer than 2 x 8 on every map; 8 x 1 beats 4 x 8 on grille" in text


def test_storage_compares_float32_and_8_bits_with_the_upload(root):
    text = docs.storage_body(root)
    assert "takes +0.10 % of float32's fetches" in text
    assert "Donnelly's 8 bits take +1.0 to +2.0 % of float16's (SIMD-tile at most +3.0 %)" in text
    assert "by up to 0.50 texel (bricks: 1.00 → 1.50)" in text


def test_pits_finds_the_largest_saving_and_donnellys_error(root):
    text = docs.pits_body(root)
    assert ("1 x 1 bins: at most -5.0 % of all rays' fetches (-10.0 % of the rays that enter a hole), on holes 16 "
            "(holes 25.6 texels deep) at 15°; at 45° and beyond at most -1.0 %") in text
    assert "moves by at most 0.20 texel with the condition" in text


def test_formats_is_the_reports_table(root):
    text = docs.formats_body(root)
    assert "| `distance` | 32.0 | 0.50 / ~2.00 | 6.0 / 9.0 / 3.50 |" in text
