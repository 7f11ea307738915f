"""``wgpuviewer refined-distance``: fetches per pixel of the distance tracer on every distance-map variant (the
paper's visibility condition off and on), on the benchmark's full-screen views (wgpuviewer.lab.bench.view) up to
grazing angles, mean and SIMD-tile (``accuracy.simd_tile_cost``), with the build time and memory of each map;
Donnelly's fixed-budget regime beside the exact one (donnelly.py); memory, build time and cost to the exact hit of
every auxiliary map format (formats.py). Variants no technique binds are traced by the numpy twin of the tracer
(tracer.py); the two registered techniques also by the GPU renderer, side by side, as the check.
"""

from __future__ import annotations

import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from maptools.cache import cached_generate
from maptools.volume.slot import DISTANCE_SLICES
from wgpuviewer.core.io import write_bytes
from wgpuviewer.lab.harness import suite as harness_suite
from wgpuviewer.lab.harness.header import Clock, Header
from wgpuviewer.lab.harness.table import Column, Table
from wgpuviewer.relief.accuracy import simd_tile_cost
from wgpuviewer.relief.maps import depth_range

from . import bounded, donnelly, example, formats, pits, reliefs
from .baseline import plain_before
from .report import PLOT, Results, plot, report
from .tracer import trace
from .variants import BEFORE, DONNELLY_VARIANTS, STORAGES, Variant, variants


@dataclass(frozen=True)
class Suite(harness_suite.Suite):
    heightmaps: tuple[str, ...]
    angles: tuple[float, ...]
    resolution: tuple[int, int]
    builtin_size: int  # texels per side of the builtin and generated maps
    #: Donnelly's regime: random rays per map and angle, the angles, the fixed budgets (iterations)
    donnelly_rays: int
    donnelly_angles: tuple[float, ...]
    budgets: tuple[int, ...]
    #: the map formats: sizes built (texels per side), the longest build run (s), the height maps and angles of
    #: the cost to the exact hit (GPU renderer), timed frames per configuration
    format_sizes: tuple[int, ...]
    format_budget_s: float
    format_maps: tuple[str, ...]
    format_angles: tuple[float, ...]
    frames: int
    #: the deeper plates (pits.py): texels per side, angles, random rays per plate and angle, Donnelly's budget
    pit_size: int
    pit_angles: tuple[float, ...]
    pit_rays: int
    pit_budget: int
    #: the refined map bounded (bounded.py), on its own maps whatever --heightmaps says: the maps, texels per side,
    #: angles, random rays per texel and bin per batch, batches, fresh rays of the check (over all bins)
    exact_maps: tuple[str, ...]
    exact_size: int
    exact_angles: tuple[float, ...]
    exact_rays: int
    exact_batches: int
    exact_checks: int


SUITES = harness_suite.suites(
    Suite("smoke", ("bricks", "plate"), (45.0, 87.0), (32, 16), 32, 256, (60.0,), (8, 64), (32, 64), 30.0,
          ("plate",), (45.0, 89.0), 2, 32, (15.0,), 400, 8, ("plate",), 16, (60.0,), 4, 2, 256),
    Suite("full", ("brick", "grass", "gravel", "bricks", "bumps", "ridges", "wall", *reliefs.NAMES),
          (0.0, 30.0, 45.0, 60.0, 75.0, 80.0, 85.0, 87.0, 89.0), (256, 144), 256, 4096, (45.0, 60.0, 75.0, 85.0),
          (8, 16, 32, 64), (256, 512, 1024), 60.0, ("bricks", "plate"), (45.0, 60.0, 75.0, 85.0, 89.0), 5,
          128, (0.0, 15.0, 30.0, 45.0, 60.0), 20000, 8, tuple(bounded.CLASSES), 64, (30.0, 45.0, 60.0, 75.0, 80.0),
          64, 4, 65536),
)

#: results.csv: one row per height map x variant x angle x tracer (the numpy twin; the GPU renderer where a
#: technique renders the variant).
TABLE = Table("refined-distance results", (
    Column("heightmap", str), Column("size", str, "texels, WxH"), Column("angle", float, "degrees"),
    Column("variant", str), Column("tracer", str), Column("fetches_mean", float, "fetches per pixel"),
    Column("fetches_simd", float, "fetches per SIMD tile of 8x4 pixels"), Column("capped", float, "of the pixels"),
    Column("build_s", float, "seconds, cache included"), Column("memory_mib", float, "MiB"),
))

#: donnelly.csv: per height map x angle x variant, Donnelly's loop at each fixed budget and the exact tracer.
DONNELLY_TABLE = Table("refined-distance Donnelly regime", (
    Column("heightmap", str), Column("size", str, "texels, WxH"), Column("angle", float, "degrees"),
    Column("variant", str), Column("regime", str, "fixed (trilinear, no finish) or exact (the tracer twin)"),
    Column("iterations", int, "fixed budget; empty for the exact tracer"),
    Column("fetches_mean", float, "volume fetches (+ cell gathers) per ray"),
    Column("error_p95", float, "texels"), Column("error_max", float, "texels"),
    Column("passed", float, "of the rays: the point reached lies past the exact hit"), Column("rays", int),
))

#: formats.csv: per map format x backend x size, the build time and the uploaded bytes per texel.
FORMATS_TABLE = Table("refined-distance map formats", (
    Column("format", str), Column("size", int, "texels per side"), Column("backend", str),
    Column("build_s", float, "seconds, uncached"), Column("extrapolated", bool, "estimated, not run"),
    Column("bytes_per_texel", float, "bytes of the uploaded texture(s) per height-map texel"),
    Column("settings", str),
))

#: format_costs.csv: the GPU renderer's cost to the exact hit per map format (its technique) and angle.
COSTS_TABLE = Table("refined-distance format costs", (
    Column("heightmap", str), Column("size", str, "texels, WxH"), Column("format", str), Column("angle", float),
    Column("fetches_mean", float, "fetches per pixel"), Column("fetches_simd", float, "per SIMD tile of 8x4"),
    Column("capped", float, "of the pixels"), Column("ms", float, "median ms per frame (software adapter: ratios)"),
))

#: The report's title (harness.header).
TITLE = "Distance-map variants: fetches per pixel (mean / SIMD-tile 8x4)"



def _build(variant: Variant, height: np.ndarray, height_scale: float) -> tuple[np.ndarray, float, int]:
    """The variant's volumes (as the tracer reads them), the build's seconds and the bytes they take."""
    t0 = time.perf_counter()
    if variant.kind == BEFORE:
        out = plain_before(height, slices=DISTANCE_SLICES, height_scale=height_scale)
        return out, time.perf_counter() - t0, out.nbytes
    out = cached_generate(variant.kind, height, backend="auto", slices=DISTANCE_SLICES, height_scale=height_scale,
                          **variant.options)
    seconds = time.perf_counter() - t0
    if variant.storage:
        store, size = STORAGES[variant.storage]
        return store(out), seconds, out.size * size
    return out, seconds, out.nbytes


def load(name: str, size: int, workdir: Path):
    """A benchmark height map or a generated one (reliefs.NAMES) at ``size``² (builtins and generated)."""
    from wgpuviewer.lab.bench.view import load_heightmap

    return reliefs.load(name, size, workdir) if name in reliefs.NAMES else load_heightmap(name, size, workdir)



def run(suite_name: str, out: Path, heightmaps=None, angles=None, backend: str | None = None,
        progress: bool = True, command: str = "wgpuviewer refined-distance", only: str = "") -> Results:
    """Measure every variant of ``SUITES[suite_name]``, Donnelly's regime and the map formats; write ``out``/
    results.csv, donnelly.csv, formats.csv, format_costs.csv, the picture and report.md (after each part). First
    the worked example and the bound (example.csv, bounded.csv, bounded_maps.csv), alone with ``only="bounded"``."""
    from tqdm import tqdm

    from wgpuviewer.core.gpu import get_gpu
    from wgpuviewer.lab.bench.run import REAL_MAPS, skimage_available

    suite = harness_suite.pick(SUITES, suite_name)
    clock = Clock()
    maps = tuple(heightmaps or suite.heightmaps)
    if heightmaps is None and not skimage_available():
        maps = tuple(m for m in maps if m not in REAL_MAPS)
    gpu = get_gpu(backend, quiet=True)
    res = Results([], [], [], [], [])
    out = Path(out)  # checked and made by the command first (harness.study.run_study)

    def write():
        _write(out, res, clock.header(TITLE, command, gpu.summary, suite.name), only)

    chosen = variants()
    format_maps = tuple(m for m in suite.format_maps if heightmaps is None or m in maps) or maps[:1]
    exact_maps = tuple(m for m in suite.exact_maps if m not in REAL_MAPS or skimage_available())
    steps = len(exact_maps) + (0 if only else len(maps) * (len(chosen) + 1) + len(formats.FORMATS) +
                               len(format_maps) + len(pits.PLATES))
    with tempfile.TemporaryDirectory(prefix="wgpuviewer-refined-") as workdir, \
            tqdm(total=steps, desc="refined-distance", unit="step", disable=not progress) as bar:
        _bound(res, suite, exact_maps, {v.name: v for v in chosen}, out, write, bar)
        if not only:
            _main(res, suite, maps, chosen, angles, format_maps, gpu, Path(workdir), write, bar)
    return res


def _bound(res: Results, suite: Suite, exact_maps, by_name: dict, out: Path, write, bar) -> None:
    """The paper's worked example (example.csv, its picture) and the exact-visibility bound on ``exact_maps``."""
    from wgpuviewer.lab.bench.view import HEIGHT_SCALE

    res.example = example.solve()
    res.cuts = {n: example.conservative_cut(n) for n in example.CUT_SECTORS}
    res.example_plotted = example.plot(res.example, res.cuts, out / example.PLOT)
    example.TABLE.write(out / "example.csv", [example.row(res.example, res.cuts)])
    for name in exact_maps:
        rows, bound = bounded.measure(name, suite, lambda v, h: _build(by_name[v], h, HEIGHT_SCALE)[0])
        res.bounded += rows
        res.bounded_maps += bound
        bar.update()
        write()


def _main(res: Results, suite: Suite, maps, chosen, angles, format_maps, gpu, workdir: Path, write, bar) -> None:
    """Every variant on the main maps with Donnelly's regime, the deeper plates, the map formats and their costs."""
    for name in maps:
        heightmap = load(name, suite.builtin_size, workdir)
        _variants(res.rows, heightmap, chosen, suite, angles, gpu, bar)
        res.donnelly += _donnelly(heightmap, chosen, suite, gpu)
        bar.update()
        write()

    def plate_done(rows: list[dict]) -> None:
        res.pits.extend(rows)
        bar.update()
        write()

    def build(height, height_scale, **options):
        return cached_generate("distance_refined", height, backend="auto", slices=pits.SLICES,
                               height_scale=height_scale, **options)

    pits.measure(suite.pit_size, suite.pit_angles, suite.pit_rays, suite.pit_budget, build, plate_done)
    heights = {n: formats_height(format_maps[0], n, workdir) for n in suite.format_sizes}

    def built(b: formats.Built) -> None:
        res.formats.append(vars(b))
        write()

    formats.measure(heights, gpu, suite.format_budget_s, on_built=built)
    bar.update(len(formats.FORMATS))
    for name in format_maps:
        res.costs += _costs(load(name, suite.builtin_size, workdir), suite, gpu)
        bar.update()
        write()


def formats_height(name: str, size: int, workdir: Path) -> np.ndarray:
    """The height map the formats are built from at ``size``²: generated and builtin maps at that size, a
    scikit-image map tiled (2x2) or cropped to it."""
    if name in reliefs.NAMES:
        return reliefs.GENERATORS[name](size)
    height = load(name, size, workdir).height
    reps = -(-size // min(height.shape))
    return np.tile(height, (reps, reps))[:size, :size]


def _variants(rows: list[dict], heightmap, chosen, suite: Suite, angles, gpu, bar) -> None:
    from wgpuviewer.lab.bench.view import HEIGHT_SCALE, make_view
    from wgpuviewer.relief.renderer import DrawConfig, Renderer

    depth = 1.0 - heightmap.height.astype(np.float64)
    depth_min = depth_range(depth, gpu.depth_format)[0]  # where the GPU tracer starts
    views = [make_view(heightmap, a, suite.resolution) for a in (angles or suite.angles)]
    for variant in chosen:
        volumes, seconds, nbytes = _build(variant, heightmap.height, HEIGHT_SCALE)
        for view in views:
            covered = np.ones(view.uv0.shape[:2], bool)
            got = trace(depth, volumes, view.uv0.reshape(-1, 2), view.v_ts.reshape(-1, 3), HEIGHT_SCALE,
                        depth_min=depth_min, **variant.bins())
            rows.append(_row(heightmap, view, variant.name, "numpy twin", got.fetches.reshape(covered.shape),
                             covered, got.capped, seconds, nbytes))
            if variant.technique:
                image = Renderer(view.scene, gpu).render(DrawConfig.of(variant.technique), suite.resolution)
                fetches, capped = _gpu_fetches(image)
                rows.append(_row(heightmap, view, variant.name, f"GPU ({gpu.summary})", fetches, image.covered,
                                 capped, seconds, nbytes))
        bar.update()


def _gpu_fetches(image) -> tuple[np.ndarray, np.ndarray]:
    """Fetches per pixel and the capped pixels (covered ones) of a render: alpha is the count, negated minus one
    where the cap stopped the ray."""
    raw = image.data[:, :, 3]
    return np.where(raw < 0, -raw - 1.0, raw), raw[image.covered] < 0


def _row(heightmap, view, variant, tracer, fetches, covered, capped, seconds, nbytes) -> dict:
    return {"heightmap": heightmap.name, "size": f"{heightmap.size[0]}x{heightmap.size[1]}", "angle": view.angle,
            "variant": variant, "tracer": tracer,
            "fetches_mean": float(np.mean(fetches[covered])), "fetches_simd": simd_tile_cost(fetches, covered=covered),
            "capped": float(np.mean(capped)), "build_s": seconds, "memory_mib": nbytes / 2**20}


def _donnelly(heightmap, chosen, suite: Suite, gpu) -> list[dict]:
    """Donnelly's loop at every fixed budget and the exact tracer (the twin), on random rays at each angle."""
    from wgpuviewer.lab.bench.view import HEIGHT_SCALE
    from wgpuviewer.relief.accuracy import random_rays
    from wgpuviewer.relief.reference import exact_hit

    depth = 1.0 - heightmap.height.astype(np.float64)
    depth_min = depth_range(depth, gpu.depth_format)[0]
    size = heightmap.size
    base = {"heightmap": heightmap.name, "size": f"{size[0]}x{size[1]}"}
    rows = []
    for angle in suite.donnelly_angles:
        uv, v = random_rays(suite.donnelly_rays, angle, seed=round(angle))
        exact = exact_hit(depth, uv, v, HEIGHT_SCALE)
        for variant in (c for c in chosen if c.name in DONNELLY_VARIANTS):
            volumes, _, _ = _build(variant, heightmap.height, HEIGHT_SCALE)
            for budget in suite.budgets:
                marched = donnelly.march(volumes, uv, v, HEIGHT_SCALE, budget, **variant.bins())
                acc = donnelly.accuracy(marched, exact.t, exact.uv, size, v, HEIGHT_SCALE)
                rows.append({**base, "angle": angle, "variant": variant.name, "regime": "fixed", "iterations": budget,
                             "fetches_mean": float(budget), "error_p95": acc.p95, "error_max": acc.max,
                             "passed": acc.passed, "rays": acc.rays})
            got = trace(depth, volumes, uv, v, HEIGHT_SCALE, depth_min=depth_min, **variant.bins())
            t = np.where(np.isnan(got.t), 1.0, got.t)
            acc = donnelly.accuracy(donnelly.Marched(t, uv - v[:, :2] / v[:, 2:3] * HEIGHT_SCALE * t[:, None]),
                                    exact.t, exact.uv, size, v, HEIGHT_SCALE)
            rows.append({**base, "angle": angle, "variant": variant.name, "regime": "exact", "iterations": None,
                         "fetches_mean": float(got.fetches.mean()), "error_p95": acc.p95, "error_max": acc.max,
                         "passed": acc.passed, "rays": acc.rays})
    return rows


#: The technique that traces each map format.
FORMAT_TECHNIQUES = {"distance": "distance", "distance_refined": "distance_refined", "cone": "cone",
                     "maxmip": "maxmip", "quadmax": "quadmax"}


def _costs(heightmap, suite: Suite, gpu) -> list[dict]:
    """Per map format, the GPU renderer's fetches (mean, SIMD-tile), capped pixels and frame time at each angle."""
    from wgpuviewer.lab.bench.config_timing import time_configs
    from wgpuviewer.lab.bench.view import make_view
    from wgpuviewer.relief.renderer import DrawConfig, Renderer

    rows = []
    for angle in suite.format_angles:
        view = make_view(heightmap, angle, suite.resolution)
        renderer = Renderer(view.scene, gpu)
        timing = time_configs(renderer, [(t, {}) for t in FORMAT_TECHNIQUES.values()], suite.resolution,
                              suite.frames, 1)
        for (fmt, technique), timed in zip(FORMAT_TECHNIQUES.items(), timing.results):
            image = renderer.render(DrawConfig.of(technique), suite.resolution)
            fetches, capped = _gpu_fetches(image)
            rows.append({"heightmap": heightmap.name, "size": f"{heightmap.size[0]}x{heightmap.size[1]}",
                         "format": fmt, "angle": angle, "fetches_mean": float(np.mean(fetches[image.covered])),
                         "fetches_simd": simd_tile_cost(fetches, covered=image.covered),
                         "capped": float(np.mean(capped)), "ms": timed.median_ms})
    return rows



def _write(out: Path, res: Results, header: Header, only: str = "") -> None:
    """The CSV files, the picture and report.md of the results so far (rewritten after each part); with ``only``
    the bound's files alone."""
    if res.bounded:
        bounded.TABLE.write(out / "bounded.csv", res.bounded)
        bounded.MAPS_TABLE.write(out / "bounded_maps.csv", res.bounded_maps)
    if only:
        write_bytes(out / "report.md", report(res, header, None).encode())
        return
    TABLE.write(out / "results.csv", res.rows)
    DONNELLY_TABLE.write(out / "donnelly.csv", res.donnelly)
    FORMATS_TABLE.write(out / "formats.csv", res.formats)
    COSTS_TABLE.write(out / "format_costs.csv", res.costs)
    if res.pits:
        pits.TABLE.write(out / "pits.csv", res.pits)
    plotted = plot(res.rows, out / PLOT)
    write_bytes(out / "report.md", report(res, header, plotted).encode())
