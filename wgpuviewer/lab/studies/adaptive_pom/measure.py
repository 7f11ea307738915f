"""The adaptive-POM study's measurement: suites, configurations, per-ray errors and fetches, results.csv's rows (``run``
then runs ``compare`` and ``report`` on them).

Rays: a grid of entry points over the whole map (``Suite.grid``, neighbours in 8 x 4 SIMD tiles as pixels are), one
view direction per angle at the benchmark's azimuth and relief depth (``bench.view``). Each ray's exact first hit
(``reference.exact_hit``) is the truth; each configuration's hit and depth fetches come from the probe
(``relief.probe``: the renderer's WGSL search). A ray the reference declines is left out of every configuration; a
ray a configuration caps counts in its fetches and not in its error.
"""

from __future__ import annotations

import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from wgpuviewer.lab.bench.run import REAL_MAPS, SYNTHETIC_MAPS
from wgpuviewer.lab.bench.view import AZIMUTH, HEIGHT_SCALE, load_heightmap
from wgpuviewer.lab.harness import suite as harness_suite
from wgpuviewer.lab.harness.header import Clock
from wgpuviewer.lab.harness.table import Column, Table
from wgpuviewer.relief import reference as ref
from wgpuviewer.relief.probe import probe

TITLE = "Adaptive POM against POM at equal error"
TILE = (8, 4)  # SIMD tile (columns, rows of the ray grid)
POM_LAYERS = (4, 6, 8, 12, 16, 24, 32, 48, 64, 96, 128, 256)
NMIN = (2, 4, 8)
NMAX = (16, 32, 64)
DEGENERATE = ("flat0", "flat1", "spike")  # constant or one-texel relief: every search is exact or none can be


@dataclass(frozen=True)
class Suite(harness_suite.Suite):
    heightmaps: tuple[str, ...]
    angles: tuple[float, ...]
    grid: tuple[int, int]  # rays (columns, rows) over the map; multiples of TILE
    builtin_size: int
    real_size: int
    resamples: int  # bootstrap resamples of the SIMD tiles


SUITES = harness_suite.suites(
    Suite("smoke", ("bricks", "spike"), (45.0, 80.0), (16, 16), 48, 64, 20),
    Suite("full", REAL_MAPS + SYNTHETIC_MAPS, (0.0, 30.0, 45.0, 60.0, 75.0, 80.0), (128, 128), 256, 256, 100),
)


@dataclass(frozen=True)
class Config:
    technique: str
    params: tuple[tuple[str, object], ...]

    @property
    def label(self) -> str:
        p = dict(self.params)
        if self.technique == "pom":
            return f"pom {p['layers']}"
        return f"adaptive{' angle-only' if p['angle_only'] else ''} {p['min_layers']}-{p['max_layers']}"


CONFIGS = ([Config("pom", (("layers", n),)) for n in POM_LAYERS] +
           [Config("pom_adaptive", (("min_layers", a), ("max_layers", b), ("angle_only", only)))
            for only in (False, True) for a in NMIN for b in NMAX])

TABLE = Table("adaptive POM results", [
    Column("heightmap", str), Column("angle", float, "degrees from the normal"), Column("technique", str),
    Column("config", str), Column("layers", int, "pom layers", optional=True),
    Column("min_layers", int, "", optional=True), Column("max_layers", int, "", optional=True),
    Column("angle_only", bool, "", optional=True), Column("rays", int, "rays with an exact hit"),
    Column("capped", float, "fraction of the rays capped"), Column("p95", float, "texels"),
    Column("p99", float, "texels"), Column("max", float, "texels"), Column("fetches", float, "mean per ray"),
    Column("fetches_simd", float, "mean over SIMD tiles of the tile's largest count"),
])


def rays(grid: tuple[int, int]) -> tuple[np.ndarray, np.ndarray]:
    """Entry uv (H*W, 2) at the grid's cell centres, row by row, and each ray's SIMD tile index (H*W,)."""
    w, h = grid
    u, v = np.meshgrid((np.arange(w) + 0.5) / w, (np.arange(h) + 0.5) / h)
    col, row = np.meshgrid(np.arange(w) // TILE[0], np.arange(h) // TILE[1])
    return np.stack([u.ravel(), v.ravel()], axis=1), (row * (w // TILE[0]) + col).ravel()


@dataclass
class ViewData:
    """One map at one angle: per configuration its rays' errors (NaN: capped) and its tiles' largest fetch counts."""

    heightmap: str
    angle: float
    errors: np.ndarray  # (configs, rays with an exact hit)
    tile_max: np.ndarray  # (configs, tiles)
    tile_of: np.ndarray  # (rays with an exact hit,) tile index
    capped: np.ndarray  # (configs,) fraction capped
    fetches: np.ndarray  # (configs,) mean per ray


def measure_view(name: str, height: np.ndarray, angle: float, suite: Suite, backend: str | None) -> ViewData:
    uv, tile_of = rays(suite.grid)
    view = ref.view_dir_from_angles(angle, AZIMUTH)
    exact = ref.exact_hit(1.0 - height, uv, view, HEIGHT_SCALE)
    ok = exact.valid
    size = (height.shape[1], height.shape[0])
    tiles = int(tile_of.max()) + 1
    errors, tile_max, capped, fetches = [], [], [], []
    for config in CONFIGS:
        hit = probe(config.technique, height, uv, view, HEIGHT_SCALE, backend=backend, **dict(config.params))
        error = ref.uv_error_texels(hit.uv, np.where(ok[:, None], exact.uv, 0.0), size)
        errors.append(np.where(hit.capped, np.nan, error)[ok])
        f = hit.fetches.astype(np.float64)
        peaks = np.full(tiles, -np.inf)
        np.maximum.at(peaks, tile_of, f)
        tile_max.append(peaks)
        capped.append(float(hit.capped[ok].mean()) if ok.any() else 0.0)
        fetches.append(float(f.mean()))
    return ViewData(name, angle, np.array(errors), np.array(tile_max), tile_of[ok], np.array(capped),
                    np.array(fetches))


def rows_of(data: ViewData) -> list[dict]:
    rows = []
    for i, config in enumerate(CONFIGS):
        e = data.errors[i]
        p95, p99, top = (np.nanpercentile(e, (95, 99, 100)) if np.isfinite(e).any() else (np.nan,) * 3)
        rows.append({**TABLE.blank(), "heightmap": data.heightmap, "angle": data.angle,
                     "technique": config.technique, "config": config.label, **dict(config.params),
                     "rays": int(e.size), "capped": data.capped[i], "p95": p95, "p99": p99, "max": top,
                     "fetches": data.fetches[i], "fetches_simd": float(data.tile_max[i].mean())})
    return rows


def measure(suite_name: str, backend: str | None, progress: bool) -> tuple[Suite, list[dict], list[ViewData], Clock]:
    """Every map and angle of the suite: results.csv's rows and each view's per-ray data (``compare`` takes them)."""
    import tempfile

    suite = harness_suite.pick(SUITES, suite_name)
    clock = Clock()
    rows, views = [], []
    with tempfile.TemporaryDirectory() as workdir:
        for name in suite.heightmaps:
            height = load_heightmap(name, suite.builtin_size, Path(workdir), suite.real_size).height
            for angle in suite.angles:
                data = measure_view(name, np.asarray(height, np.float64), angle, suite, backend)
                views.append(data)
                rows += rows_of(data)
                if progress:
                    print(f"adaptive-pom: {name} {angle:g}°", file=sys.stderr)
    return suite, rows, views, clock
