"""bench's blocks on docs/techniques.md (``lab.bench.docs``) compute what they say from a results file: synthetic
rows with known answers, written as bench writes them; and auto's table block says what auto's code holds."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from wgpuviewer.lab.bench import docs
from wgpuviewer.lab.bench.run import TABLE
from wgpuviewer.techniques.auto import autotable

FOLDER = "run"
QUADMAX = ("quadmax", "top_offset=-2 max_steps=1024")
DISTANCE = ("distance", "iterations=256")


def row(heightmap, key, angle, *, ratio=1.0, simd=0.0, p95=0.0, capped=0.0, mean=None, adapter="test adapter"):
    r = TABLE.blank()
    r.update(suite="full", heightmap=heightmap, heightmap_size="64x64", technique=key[0], params=key[1],
             angle=angle, angle_min=angle, angle_max=angle, resolution="8x8", adapter=adapter, backend="Vulkan",
             timer="timestamp", frames=1, gpu_ms=ratio, basic_ms=1.0, ratio_to_basic=ratio,
             fetches_mean=simd if mean is None else mean, fetches_p95=simd, uv_err_mean=p95, uv_err_p95=p95,
             uv_err_max=p95, psnr_db=40.0, capped_fraction=capped, covered_fraction=1.0, eval_pixels=64,
             fetches_simd=simd, simd_tile="8x4", map_bytes=0)
    return r


@pytest.fixture
def root(tmp_path) -> Path:
    return tmp_path


def write(root: Path, rows) -> None:
    (root / FOLDER).mkdir(parents=True, exist_ok=True)
    TABLE.write(root / FOLDER / "results.csv", rows)


def table_row(text: str, first_cell: str) -> list[str]:
    line = next(line for line in text.splitlines() if line.startswith(f"| {first_cell} |"))
    return [cell.strip() for cell in line.strip("|").split("|")][1:]


def test_angle_table_means_the_fetches_and_takes_the_worst_p95(root):
    pom = ("pom", "layers=32")
    write(root, [row("a", pom, 45.0, simd=10.0, p95=0.5), row("b", pom, 45.0, simd=20.0, p95=12.0),
                 row("a", pom, 80.0, simd=4.0, p95=0.25), row("b", QUADMAX, 45.0, simd=7.0)])
    text = docs.angle_table(root, FOLDER, (pom, QUADMAX), (45.0, 80.0))
    assert table_row(text, "pom layers=32") == ["15.0 / 12.0", "4.0 / 0.25"]
    assert table_row(text, "quadmax top_offset=-2 max_steps=1024") == ["7.0 / 0.00", "–"]


def test_grazing_table_gives_mean_fetches_and_the_capped_share(root):
    write(root, [row("a", ("maxmip", "max_steps=1024"), 85.0, simd=30.0, mean=25.5),
                 row("a", ("maxmip", "max_steps=1024"), 89.0, simd=50.0, mean=44.1, capped=0.02),
                 row("a", ("maxmip", "max_steps=1024"), 60.0, simd=9.0, mean=9.0, capped=0.5)])
    text = docs.grazing_table(root, FOLDER, ("maxmip", "cone"), (85.0, 89.0))
    assert table_row(text, "a") == ["25.5 / 44.1 (2.0% capped)", "– / –"]
    assert text.splitlines()[-1] == "Capped rays in 1 of 2 rows, at most 2.0%."


def test_time_per_fetch_is_over_basic_per_simd_fetch_and_in_pom_fetches(root):
    rows = []
    for m, scale in (("a", 1.0), ("b", 2.0)):
        rows += [row(m, ("pom", "layers=16"), 45.0, simd=10.0 * scale, ratio=1.0 + 0.1 * 10.0 * scale),
                 row(m, QUADMAX, 45.0, simd=5.0 * scale, ratio=1.0 + 0.3 * 5.0 * scale),
                 row(m, DISTANCE, 45.0, simd=10.0 * scale, ratio=2.0 * (1.0 + 0.3 * 5.0 * scale))]
    write(root, rows)
    text = docs.fetch_cost_body(root, FOLDER)
    assert table_row(text, "pom") == ["0.100", "1.00", f"{autotable.COST_WEIGHTS['pom']:g}"]
    assert table_row(text, "quadmax") == ["0.300", "3.00", f"{autotable.COST_WEIGHTS['quadmax']:g}"]
    assert table_row(text, "distance")[2] == "–"  # not one of auto's candidates
    assert "45°: 2.0× the SIMD-tile fetches, 2.00× the time." in text


def test_auto_beyond_the_headline_angle_takes_the_worst_map_and_marks_the_budget(root):
    auto = ("auto", "max_error=0.25 max_error_px=0.0")
    write(root, [row("a", auto, 85.0, p95=0.3), row("b", auto, 85.0, p95=0.1), row("a", auto, 89.0, p95=0.2),
                 row("a", auto, 80.0, p95=5.0)])
    text = docs.auto_beyond_body(root, FOLDER)
    assert "| 85° | 89° |" in text and "80°" not in text.split("\n", 1)[1]
    assert table_row(text, "auto max_error=0.25 max_error_px=0.0") == ["**0.30 (a)**", "0.20 (a)"]


def test_switch_cost_is_each_map_at_zero_degrees(root):
    auto = ("auto", "max_error=0.5 max_error_px=0.0")
    write(root, [row("a", ("normal", "-"), 0.0, ratio=1.1), row("a", auto, 0.0, ratio=2.4, simd=0.2),
                 row("a", auto, 45.0, ratio=9.0)])
    text = docs.switch_cost_body(root, FOLDER)
    assert table_row(text, "a") == ["1.10× (0.0)", "–", "2.40× (0.2)"]


def test_auto_table_says_what_auto_code_holds():
    text = docs.auto_table_body(Path("."))
    assert f"**{len(autotable.AUTO_CANDIDATES)} candidates**" in text
    names = text.split("cheapest first: ", 1)[1].split(" (relief n+b", 1)[0].split(", ")
    assert names[0] == "basic" and names[-1] == "quadmax" and len(names) == len(autotable.AUTO_CANDIDATES)
    assert "POM 16" in names and "relief 8+2" in names
    first = math.degrees(math.atan(autotable.AUTO_TAN0))
    last = math.degrees(math.atan(autotable.AUTO_TAN0 * 2.0 ** ((autotable.AUTO_BINS - 2) / autotable.AUTO_BINS_PER_OCTAVE)))
    assert f"bin 0 below {first:.2f}°, the last from {last:.1f}° on" in text
    assert f"**{autotable.AUTO_BUDGET_LEVELS} budgets**: 0.0625," in text
    assert f"quadmax {autotable.COST_WEIGHTS['quadmax']:g}." in text


def test_a_folder_without_results_says_so(root):
    assert "holds no results" in docs.angle_table(root, FOLDER, (QUADMAX,), (45.0,))
