"""The accuracy study's measurement: suites, results.csv (the probe against the float64 exact hit), shadows.csv
(self-shadowing) and report.md.

Per builtin height map (``--texels`` square) and suite angle, ``rays`` random rays (``relief.accuracy.random_rays``,
seed 0) traced once by the float64 reference and by every setting's probe (``relief.accuracy.run``); per light
elevation, every shadowing technique's hard and soft shadow of its own view hits (``relief.accuracy.shadow_run``).
The report is made from the rows read back from the CSV files, so it and the docs show the same numbers.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from wgpuviewer.core.gpu import get_gpu
from wgpuviewer.core.io import write_bytes
from wgpuviewer.lab.harness import suite as harness_suite
from wgpuviewer.lab.harness.header import Clock
from wgpuviewer.lab.harness.table import Column, Table
from wgpuviewer.relief import accuracy
from wgpuviewer.textures import builtin_height

from .command import DEFAULT_HEIGHTMAPS
from .report import label, report

TITLE = "Probe accuracy: every ray-search technique against the float64 exact hit"


@dataclass(frozen=True)
class Suite(harness_suite.Suite):
    angles: tuple[float, ...]  # view angles, degrees from the normal
    elevations: tuple[float, ...]  # light elevations of the self-shadowing, degrees above the surface


SUITES = harness_suite.suites(
    Suite("smoke", (30.0, 80.0), (45.0,)),
    Suite("full", accuracy.DEFAULT_ANGLES, accuracy.SHADOW_ELEVATIONS),
)

RESULTS = Table("accuracy results", [
    Column("heightmap", str), Column("width", int, "texels"), Column("height", int, "texels"),
    Column("height_scale", float, "relief depth in UV units"),
    Column("rays", int, "random rays per map and angle, the same for every setting"),
    Column("angle", float, "degrees from the normal"), Column("technique", str),
    Column("params", str, "the overrides of the technique's defaults, '-' for none"),
    Column("error_mean", float, "texels (wrap-aware), over the rays not capped"),
    Column("error_p95", float, "texels"), Column("error_max", float, "texels"),
    Column("fetches_mean", float, "fetches per ray, as the technique counts them"),
    Column("fetches_p95", float, "fetches per ray"),
    Column("capped", float, "fraction of the rays flagged capped"),
])

SHADOWS = Table("accuracy self-shadowing results", [
    Column("heightmap", str), Column("technique", str),
    Column("elevation", float, "light, degrees above the surface"),
    Column("light_azimuth", float, "light, tangent-space degrees"),
    Column("view_angle", float, "view rays, degrees from the normal"),
    Column("rays", int, "random view rays per map"),
    Column("valid_rays", int, "the rays with an exact hit: those scored"),
    Column("ref_lit", float, "fraction of the rays the reference lights"),
    Column("hard_wrong", float, "fraction with the wrong hard state, cast from the exact hit"),
    Column("hard_wrong_own_hit", float, "the same, cast from the technique's own view hit"),
    Column("soft_diff", float, "mean |visibility - reference|, from the exact hit"),
    Column("soft_diff_own_hit", float, "the same, from the technique's own view hit"),
    Column("hard_fetches", float, "mean depth fetches per hard shadow ray from the exact hit"),
    Column("soft_fetches", float, "mean depth fetches per soft estimate"),
    Column("view_fetches", float, "mean depth fetches per view ray"),
    Column("capped", float, "fraction of the shadow rays flagged capped"),
])


def result_rows(measured: accuracy.Run) -> list[dict]:
    """One row per height map, setting and angle, in the run's order."""
    rows = []
    for name, (h, w) in measured.heightmaps.items():
        for i, (technique, params) in enumerate(measured.settings):
            for angle in measured.angles:
                a = measured.results[name, i, angle]
                rows.append({"heightmap": name, "width": w, "height": h, "height_scale": measured.height_scale,
                             "rays": a.rays, "angle": angle, "technique": technique, "params": label(params),
                             "error_mean": a.error_mean, "error_p95": a.error_p95, "error_max": a.error_max,
                             "fetches_mean": a.fetches_mean, "fetches_p95": a.fetches_p95, "capped": a.capped})
    return rows


def shadow_rows(measured: accuracy.ShadowRun) -> list[dict]:
    """One row per height map, light elevation and technique."""
    return [{"heightmap": name, "technique": technique, "elevation": elevation,
             "light_azimuth": accuracy.LIGHT_AZIMUTH, "view_angle": measured.view_angle, "rays": measured.rays,
             "valid_rays": m.rays, "ref_lit": m.ref_lit, "hard_wrong": m.hard_wrong,
             "hard_wrong_own_hit": m.hard_wrong_own_hit, "soft_diff": m.soft_diff,
             "soft_diff_own_hit": m.soft_diff_own_hit, "hard_fetches": float(m.hard_fetches.mean()),
             "soft_fetches": m.soft_fetches, "view_fetches": m.view_fetches, "capped": m.capped}
            for (name, technique, elevation), m in measured.results.items()]


def run(out: Path, suite_name: str = "full", backend=None, progress: bool = True,
        command: str = "wgpuviewer accuracy", heightmaps=DEFAULT_HEIGHTMAPS, texels: int = 256, rays: int = 4096,
        height_scale: float = 0.05) -> None:
    """Measure, write results.csv, shadows.csv and report.md into ``out``."""
    from tqdm import tqdm

    suite = harness_suite.pick(SUITES, suite_name)
    gpu = get_gpu(backend, quiet=True)
    clock = Clock()
    maps = {name: builtin_height(name, (texels, texels)) for name in heightmaps}
    total = len(maps) * (len(suite.angles) * len(accuracy.DEFAULT_SETTINGS) +
                         len(suite.elevations) * len(accuracy.shadowing_techniques()))
    with tqdm(total=total, desc="probe vs reference", disable=not progress or None, leave=False) as bar:
        measured = accuracy.run(maps, suite.angles, height_scale=height_scale, rays=rays, backend=backend,
                                progress=bar.update)
        shadows = accuracy.shadow_run(maps, elevations=suite.elevations, height_scale=height_scale, rays=rays,
                                      backend=backend, progress=bar.update)
    RESULTS.write(out / "results.csv", result_rows(measured))
    SHADOWS.write(out / "shadows.csv", shadow_rows(shadows))
    header = clock.header(TITLE, command, gpu.summary, suite.name)
    lines = report(RESULTS.read(out / "results.csv"), SHADOWS.read(out / "shadows.csv"))
    write_bytes(out / "report.md", "\n".join([*header.lines(), *lines, ""]).encode("utf-8"))
