"""The cost measures of relief/accuracy.py and the writer of docs/accuracy.md."""

from __future__ import annotations

import numpy as np
import pytest

from wgpuviewer.core.errors import InputError
from wgpuviewer.relief.accuracy import (
    DEFAULT_SETTINGS,
    markdown_report,
    measure,
    run,
    shadow_report,
    shadow_run,
    simd_tile_cost,
)
from wgpuviewer.techniques import TECHNIQUES
from wgpuviewer.textures import builtin_height


def test_simd_tile_cost_is_the_mean_of_tile_maxima():
    f = np.zeros((4, 16))
    f[0, 0] = 10  # one slow lane makes its whole 8x4 tile pay 10
    f[:, 8:] = 3
    assert simd_tile_cost(f) == pytest.approx((10 + 3) / 2)
    assert simd_tile_cost(f, tile=(1, 1)) == pytest.approx(f.mean())  # one lane per group: the plain mean


def test_simd_tile_cost_partial_tiles_and_coverage():
    f = np.arange(5 * 9, dtype=float).reshape(5, 9)
    # tiles (8x4): rows 0-3 x cols 0-7, 0-3 x 8, 4 x 0-7, 4 x 8
    expected = np.mean([f[0:4, 0:8].max(), f[0:4, 8].max(), f[4, 0:8].max(), f[4, 8]])
    assert simd_tile_cost(f) == pytest.approx(expected)
    covered = np.zeros_like(f, bool)
    covered[0, 0] = True
    assert simd_tile_cost(f, covered=covered) == 0.0  # only the covered lane counts, in the only live tile
    assert np.isnan(simd_tile_cost(f, covered=np.zeros_like(covered)))
    with pytest.raises(InputError):
        simd_tile_cost(np.zeros(5))


def test_markdown_report_of_a_tiny_run(gpu):
    """docs/accuracy.md's writer: the command, adapter and date at the top, one table per height map with a row per
    setting and a column per angle; each cell is the measurement ``measure`` gives (the run traces the reference
    once per map and angle for all settings)."""
    maps = {"step": builtin_height("step", (16, 16)), "flat1": builtin_height("flat1", (16, 8))}
    settings = (("pom", {"layers": 4}), ("maxmip", {"max_steps": 1}))
    measured = run(maps, angles=(0.0, 60.0), settings=settings, rays=32)
    text = markdown_report(measured, command="wgpuviewer accuracy --doc x.md", adapter="Test GPU", date="2026-01-02")
    lines = text.splitlines()
    assert lines[0].startswith("# ") and "`wgpuviewer accuracy --doc x.md`" in lines[2]
    assert lines[4].startswith("Adapter: Test GPU; 2026-01-02;") and "32 random rays" in lines[4]
    headings = [i for i, line in enumerate(lines) if line.startswith("## ")]
    assert [lines[i] for i in headings] == ["## step (16x16)", "## flat1 (16x8)"]
    for i, (name, height) in zip(headings, maps.items(), strict=True):
        assert lines[i + 2] == "| technique | params | 0° | 60° |"
        rows = lines[i + 4:i + 6]
        for row, (technique, params) in zip(rows, settings, strict=True):
            cells = [c.strip() for c in row.strip("|").split("|")]
            assert cells[:2] == [technique, ", ".join(f"{k}={v}" for k, v in params.items())]
            for cell, angle in zip(cells[2:], (0.0, 60.0), strict=True):
                a = measure(technique, height, angle, rays=32, **params)
                p95, rest = cell.split(" / ")
                if np.isnan(a.error_p95):  # every ray capped
                    assert p95 == "–", (name, technique, angle)
                else:
                    assert float(p95) == pytest.approx(a.error_p95, abs=1e-3), (name, technique, angle)
                assert f"· {a.fetches_mean:.1f}" in rest and ("capped" in rest) == (a.capped > 0)
    # a map whose every ray is capped shows no error, and says so
    capped = measured.results["step", 1, 60.0]
    assert capped.capped == 1.0 and lines[headings[0] + 5].endswith("– / – · 1.0 · 100.0% capped |")


def test_accuracy_measures_every_ray_search_technique():
    """``wgpuviewer accuracy``'s settings are the registry's: each ray-search entry's accuracy_settings, in order."""
    expected = [(name, params) for name, t in TECHNIQUES.items() if t.ray_search for params in t.accuracy_settings]
    assert list(DEFAULT_SETTINGS) == expected
    assert {name for name, _ in DEFAULT_SETTINGS} == {name for name, t in TECHNIQUES.items() if t.ray_search}
    assert {"quadmax", "quadmax_pom", "auto"} <= {name for name, _ in DEFAULT_SETTINGS}


@pytest.mark.parametrize("kwargs, message", [
    (dict(rays=0), "rays = 0; expected 1 to 4194304"),
    (dict(rays=-1), "rays = -1; expected 1 to 4194304"),
    (dict(rays=10**12), "rays = 1000000000000; expected 1 to 4194304 (32 bytes a ray"),
    (dict(rays=64.0), "rays = 64.0; expected a whole number of rays"),
    (dict(angle_deg=90.0), "angle_deg = 90.0; expected 0 <= angle < 90 degrees"),
    (dict(angle_deg=-10.0), "angle_deg = -10.0; expected 0 <= angle < 90"),
    (dict(angle_deg=1e9), "angle_deg = 1000000000.0; expected 0 <= angle < 90"),
    (dict(angle_deg=float("nan")), "angle_deg = nan"),
    (dict(angle_deg="30"), "angle_deg = '30'; expected a real number"),
    (dict(height=np.full((8, 8), 0.5 + 0j)), "height has dtype complex128; expected real numbers"),
    (dict(height_scale="0.05"), "height_scale = '0.05'; expected a real number"),
])
def test_measure_refuses_what_it_cannot_use_in_one_line_before_tracing(kwargs, message, monkeypatch):
    """Like the CLI's options: an InputError naming the argument and the range, never an IndexError, a MemoryError
    or NaN statistics; nothing is traced first."""
    import wgpuviewer.relief.accuracy as accuracy

    monkeypatch.setattr(accuracy, "exact_hit", lambda *a, **k: pytest.fail("traced before the arguments were checked"))
    args = dict(technique="pom", height=np.full((8, 8), 0.5), angle_deg=30.0, rays=64)
    args.update(kwargs)
    with pytest.raises(InputError) as error:
        measure(**args)
    text = str(error.value)
    assert text.startswith("measure: ") and message in text and "\n" not in text, text
    with pytest.raises(InputError, match="run: "):  # the accuracy table's runs check the same way
        run({"m": args["height"]}, angles=(args["angle_deg"],), settings=(("pom", {}),), rays=args["rays"],
            height_scale=args.get("height_scale", 0.05))


def test_measure_at_its_largest_angle_and_ray_counts_gives_numbers(gpu):
    a = measure("pom", np.full((8, 8), 0.5), 89.9, rays=1)
    assert a.rays == 1 and np.isfinite(a.fetches_mean)


def test_shadow_report_of_a_tiny_run(gpu):
    """The report's self-shadowing table: a row per technique, a column per light; each cell the mean over the maps
    of the wrong hard states from the technique's own hits (the worst map in brackets), the soft difference and the
    shadow ray's fetches, as the run measured them. The exact tracer casts the reference's shadows."""
    maps = {"step": builtin_height("step", (16, 16)), "bricks": builtin_height("bricks", (32, 32))}
    measured = shadow_run(maps, techniques=("pom", "maxmip"), elevations=(30.0, 60.0), rays=256)
    lines = shadow_report(measured)
    assert "## Self-shadowing" in lines
    header = lines.index("| technique | light 30° | light 60° |")
    for row, technique in zip(lines[header + 2:], ("pom", "maxmip"), strict=True):
        cells = [c.strip() for c in row.strip("|").split("|")]
        assert cells[0] == technique
        for cell, elevation in zip(cells[1:], (30.0, 60.0), strict=True):
            sel = [measured.results[name, technique, elevation] for name in maps]
            wrong = [100 * m.hard_wrong_own_hit for m in sel]
            expected = (f"{np.mean(wrong):.2f} % ({max(wrong):.2f}) / "
                        f"{np.mean([m.soft_diff_own_hit for m in sel]):.4f} · "
                        f"{np.mean([m.hard_fetches.mean() for m in sel]):.1f}")
            assert cell == expected
    lit = [m.ref_lit for m in measured.results.values() if m.elevation == 30.0]
    assert min(lit) < 1.0  # shadows to get right
    assert all(m.hard_wrong <= 0.02 for (_, t, _), m in measured.results.items() if t == "maxmip")
    text = markdown_report(run(maps, angles=(0.0,), settings=(("pom", {}),), rays=8), "c", "Test GPU",
                           "2026-01-02", shadows=measured)
    assert text.rstrip().endswith(lines[-1]) and "(self-shadowing" in text.splitlines()[4]
