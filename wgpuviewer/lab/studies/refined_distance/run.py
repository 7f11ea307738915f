"""``wgpuviewer refined-distance``: fetches per pixel of the distance tracer on every distance-map variant (the
paper's visibility condition off and on), on the benchmark's full-screen views (wgpuviewer.lab.bench.view) up to
grazing angles, mean and SIMD-tile (``accuracy.simd_tile_cost``), with the build time and memory of each map;
Donnelly's fixed-budget regime beside the exact one (donnelly.py); memory, build time and cost to the exact hit of
every auxiliary map format (formats.py). Variants no technique binds are traced by the numpy twin of the tracer
(tracer.py); the two registered techniques also by the GPU renderer, side by side, as the check.
"""

from __future__ import annotations

import math
import tempfile
import time
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from maptools.cache import cached_generate
from maptools.registry import get_kind
from wgpuviewer.core.io import write_bytes
from wgpuviewer.lab.harness import suite as harness_suite
from wgpuviewer.lab.harness.header import Clock, Header
from wgpuviewer.lab.harness.plots import MISSING, pyplot, save_png
from wgpuviewer.lab.harness.table import Column, Table
from wgpuviewer.relief.accuracy import simd_tile_cost
from wgpuviewer.relief.maps import DISTANCE_SLICES, depth_range, uploaded_volume
from wgpuviewer.techniques import REFINED_BANDS, REFINED_MAX_ANGLE, REFINED_SECTORS

from . import donnelly, formats, pits, reliefs
from .baseline import plain_before
from .tracer import trace

#: The baseline's kind: not a maptools kind, built by baseline.plain_before (uncached: seconds).
BEFORE = "maptools-2 plain"


@dataclass(frozen=True)
class Variant:
    name: str
    kind: str  # maptools kind
    options: dict  # beyond slices and height_scale
    technique: str = ""  # the registered technique that renders exactly this map, if any
    storage: str = ""  # a compact storage of the values (STORAGES), "" as maptools stores them

    def bins(self) -> dict:
        """The tracer's view of the map: sectors, bands and max_angle (refined kind) or nothing (plain)."""
        if self.kind != "distance_refined":
            return {}
        return {k: self.options[k] for k in ("sectors", "bands", "max_angle")}


#: Donnelly stored his distances in 8 bits: over [0, EIGHT_BIT_RANGE] texels, larger ones stored as the range.
EIGHT_BIT_RANGE = 16.0


def _eight_bit(v: np.ndarray) -> np.ndarray:
    v = np.asarray(v, np.float64)
    return np.minimum(np.floor(np.minimum(v, EIGHT_BIT_RANGE) / EIGHT_BIT_RANGE * 255.0) * EIGHT_BIT_RANGE / 255.0, v)


#: Storages of the plain map: each value rounded DOWN to what the storage holds (a step never grows, so safety
#: holds), and its bytes per value: float16 (r16float, what the renderer uploads: relief.maps.uploaded_volume) and
#: Donnelly's 8 bits (r8unorm); maptools' own float32 is the variant without a storage.
STORAGES = {"float16": (lambda v: uploaded_volume(v).astype(np.float64), 2), "8-bit": (_eight_bit, 1)}

#: The paper's visibility condition as maptools names it (an option of the distance_refined kind).
VISIBILITY = "visibility"


def _refined(sectors: int, bands: int, technique: str = "", visibility: str = "") -> Variant:
    """A refined-map variant; ``visibility`` "on"/"off" sets the paper's condition, "" leaves the kind's default."""
    name = "single cone" if sectors == bands == 1 else f"{sectors} sectors x {bands} bands"
    options = {"sectors": sectors, "bands": bands, "max_angle": REFINED_MAX_ANGLE}
    if visibility:
        name += f", visibility {visibility}"
        options[VISIBILITY] = visibility
    return Variant(name, "distance_refined", options, technique)


VARIANTS = (
    Variant("plain before (maptools-2)", BEFORE, {}),
    Variant("plain K=1", "distance", {"subcells": 1}),
    Variant("plain K=4", "distance", {"subcells": 4}, "distance", storage="float16"),
    Variant("plain K=4, float32", "distance", {"subcells": 4}),
    Variant("plain K=4, 8-bit", "distance", {"subcells": 4}, storage="8-bit"),
    _refined(1, 1),
    _refined(8, 1),
    _refined(1, REFINED_BANDS),
    _refined(2, REFINED_BANDS),
    _refined(REFINED_SECTORS, REFINED_BANDS, "distance_refined"),
    _refined(1, 1, visibility="on"),
    _refined(REFINED_SECTORS, REFINED_BANDS, visibility="on"),
)
PRODUCT = VARIANTS[-3].name
SINGLE_CONE = next(v.name for v in VARIANTS if v.kind == "distance_refined")
PLAIN = "plain K=4"  # the product's `distance` map: the ratios' denominator
#: The paper's condition: (its map with the condition, the same map without), single cone and binned.
CONDITION_PAIRS = ((VARIANTS[-2].name, SINGLE_CONE), (VARIANTS[-1].name, PRODUCT))


def variants() -> tuple[Variant, ...]:
    """The variants measured: every refined one with its condition set ("off" where VARIANTS leaves it out), and
    the `distance_refined` technique on the product's bins with the kind's default condition (what the renderer
    builds)."""
    default = next(o.default for o in get_kind("distance_refined").options if o.name == VISIBILITY)
    out = []
    for v in VARIANTS:
        if v.kind != "distance_refined":
            out.append(v)
            continue
        opts = {VISIBILITY: "off", **v.options}
        product_bins = (opts["sectors"], opts["bands"]) == (REFINED_SECTORS, REFINED_BANDS)
        technique = "distance_refined" if product_bins and opts[VISIBILITY] == default else ""
        out.append(replace(v, options=opts, technique=technique))
    return tuple(out)


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


SUITES = harness_suite.suites(
    Suite("smoke", ("bricks", "plate"), (45.0, 87.0), (32, 16), 32, 256, (60.0,), (8, 64), (32, 64), 30.0,
          ("plate",), (45.0, 89.0), 2, 32, (15.0,), 400, 8),
    Suite("full", ("brick", "grass", "gravel", "bricks", "bumps", "ridges", "wall", *reliefs.NAMES),
          (0.0, 30.0, 45.0, 60.0, 75.0, 80.0, 85.0, 87.0, 89.0), (256, 144), 256, 4096, (45.0, 60.0, 75.0, 85.0),
          (8, 16, 32, 64), (256, 512, 1024), 60.0, ("bricks", "plate"), (45.0, 60.0, 75.0, 85.0, 89.0), 5,
          128, (0.0, 15.0, 30.0, 45.0, 60.0), 20000, 8),
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

#: Donnelly's regime is measured on these variants (those this maptools builds).
#: The plain map in maptools' float32 and in Donnelly's 8 bits (the product's is float16: PLAIN).
OTHER_STORAGES = ("plain K=4, float32", "plain K=4, 8-bit")
DONNELLY_VARIANTS = (PLAIN, SINGLE_CONE, VARIANTS[-2].name, PRODUCT, VARIANTS[-1].name, *OTHER_STORAGES)


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


@dataclass
class Results:
    rows: list[dict]
    donnelly: list[dict]
    formats: list[dict]
    costs: list[dict]
    pits: list[dict]


def run(suite_name: str, out: Path, heightmaps=None, angles=None, backend: str | None = None,
        progress: bool = True, command: str = "wgpuviewer refined-distance") -> Results:
    """Measure every variant of ``SUITES[suite_name]``, Donnelly's regime and the map formats; write ``out``/
    results.csv, donnelly.csv, formats.csv, format_costs.csv, the picture and report.md (after each part)."""
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
        _write(out, res, clock.header(TITLE, command, gpu.summary, suite.name))

    chosen = variants()
    format_maps = tuple(m for m in suite.format_maps if heightmaps is None or m in maps) or maps[:1]
    steps = len(maps) * (len(chosen) + 1) + len(formats.FORMATS) + len(format_maps) + len(pits.PLATES)
    with tempfile.TemporaryDirectory(prefix="wgpuviewer-refined-") as workdir, \
            tqdm(total=steps, desc="refined-distance", unit="step", disable=not progress) as bar:
        for name in maps:
            heightmap = load(name, suite.builtin_size, Path(workdir))
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
        heights = {n: formats_height(format_maps[0], n, Path(workdir)) for n in suite.format_sizes}

        def built(b: formats.Built) -> None:
            res.formats.append(vars(b))
            write()

        formats.measure(heights, gpu, suite.format_budget_s, on_built=built)
        bar.update(len(formats.FORMATS))
        for name in format_maps:
            res.costs += _costs(load(name, suite.builtin_size, Path(workdir)), suite, gpu)
            bar.update()
            write()
    return res


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
    from wgpuviewer.lab.bench.timing import time_configs
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


#: Files of a run (a stale one from an earlier layout is removed by the lead, not here).
PLOT = "ratio_to_distance.png"


def _write(out: Path, res: Results, header: Header) -> None:
    """The CSV files, the picture and report.md of the results so far (rewritten after each part)."""
    TABLE.write(out / "results.csv", res.rows)
    DONNELLY_TABLE.write(out / "donnelly.csv", res.donnelly)
    FORMATS_TABLE.write(out / "formats.csv", res.formats)
    COSTS_TABLE.write(out / "format_costs.csv", res.costs)
    if res.pits:
        pits.TABLE.write(out / "pits.csv", res.pits)
    plotted = plot(res.rows, out / PLOT)
    write_bytes(out / "report.md", report(res, header, plotted).encode())


def _twins(rows: list[dict]) -> list[dict]:
    return [r for r in rows if r["tracer"] == "numpy twin"]


def ratios(rows: list[dict], key: str = "fetches_mean") -> dict[tuple[str, str, float], float]:
    """(height map, variant, angle) -> the variant's ``key`` over the plain K=4 map's (the `distance` technique's)
    on the same view, numpy-twin rows."""
    twins = _twins(rows)
    plain = {(r["heightmap"], r["angle"]): r[key] for r in twins if r["variant"] == PLAIN}
    return {(r["heightmap"], r["variant"], r["angle"]): r[key] / plain[r["heightmap"], r["angle"]]
            for r in twins if (r["heightmap"], r["angle"]) in plain and plain[r["heightmap"], r["angle"]] > 0}


def plot(rows: list[dict], path: Path) -> bool:
    """Fetches per pixel over the `distance` map's (plain K=4) against the view angle: one panel per height map,
    one line per variant; the visibility-on maps dashed in the colour of their visibility-off twin. False when
    matplotlib is missing (the tables still stand)."""
    with pyplot() as plt:
        if plt is None:
            return False
        _draw(plt, rows, path)
    return True


def _draw(plt, rows: list[dict], path: Path) -> None:
    by = ratios(rows)
    maps = list(dict.fromkeys(k[0] for k in by))
    cols = min(3, len(maps)) or 1
    panel_rows = math.ceil(len(maps) / cols) or 1
    fig, axes = plt.subplots(panel_rows, cols, figsize=(4.2 * cols, 3.2 * panel_rows), squeeze=False)
    off_of = {on: off for on, off in CONDITION_PAIRS}
    names = [v.name for v in VARIANTS if v.name != PLAIN]
    colours = {n: plt.cm.tab10(i % 10) for i, n in enumerate(n for n in names if n not in off_of)}
    sizes = {r["heightmap"]: r["size"] for r in rows}
    for ax, name in zip(axes.ravel(), maps):
        for variant in names:
            mine = sorted((a, r) for (m, v, a), r in by.items() if m == name and v == variant)
            if not mine:
                continue
            angles, ratio = zip(*mine)
            on = variant in off_of
            ax.plot(angles, ratio, "--" if on else "-", marker="x" if on else "o", ms=3,
                    lw=2.0 if PRODUCT in variant else 1.1, color=colours[off_of.get(variant, variant)],
                    label=variant)
        ax.axhline(1.0, color="k", lw=0.6)
        ax.set_title(f"{name} ({sizes[name]})", fontsize=9)
        ax.set_xlabel("view angle at the frame centre (deg)", fontsize=7)
        ax.set_ylabel("fetches / distance map's", fontsize=7)
        ax.tick_params(labelsize=7)
        ax.grid()
    for ax in axes.ravel()[len(maps):]:
        ax.axis("off")
    handles, labels = axes.ravel()[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=min(4, len(labels)) or 1, fontsize=7, frameon=False)
    fig.suptitle("Fetches to the exact hit over the `distance` map's (plain K=4), mean per pixel; "
                 "dashed: the paper's visibility condition on", fontsize=9)
    fig.tight_layout(rect=(0, 0.1, 1, 0.96))
    save_png(fig, path, tight=False)


#: The report's change columns: (label, variant, against which variant).
CHANGES = (("K=4 vs before", PLAIN, VARIANTS[0].name), ("product vs before", PRODUCT, VARIANTS[0].name),
           ("product vs K=4", PRODUCT, PLAIN),
           *((f"K=4 {name.split(', ')[1]} vs float16", name, PLAIN) for name in OTHER_STORAGES))


def _pct(a: float | None, b: float | None) -> str:
    return "-" if not (a and b) else f"{100 * (a / b - 1):+.0f} %"


def _change(by: dict, variant: str, base: str) -> str:
    a, b = by.get(variant), by.get(base)
    if not (a and b):
        return "-"
    return f"{_pct(a['fetches_mean'], b['fetches_mean'])} / {_pct(a['fetches_simd'], b['fetches_simd'])}"


def report(res: Results, header: Header, plotted: bool) -> str:
    """Markdown: the paper's condition (on vs off), per height map every variant's fetches by angle with the
    changes, grazing views, Donnelly's regime, the map formats."""
    lines = [*header.lines(), "",
             "Every fetch to the final hit (volume fetches and exact-cell gathers), the same tracer (the numpy twin of "
             "`distance.wgsl`) for every map; the GPU renderer beside it where a technique binds the map. Changes: "
             "mean / SIMD-tile. " + (f"Picture (ratios to the `distance` map): [{PLOT}]({PLOT})." if plotted
                                    else MISSING), ""]
    lines += _condition_section(res.rows)
    lines += pits.section(res.pits)
    lines += _variant_sections(res.rows)
    lines += _grazing_section(res.rows)
    lines += _donnelly_section(res.donnelly)
    lines += _formats_section(res.formats, res.costs)
    return "\n".join(lines) + "\n"


def _condition_section(rows: list[dict]) -> list[str]:
    lines = ["## The paper's visibility condition", ""]
    twins = _twins(rows)
    lines += ["Fetches with the condition over the same map without it (mean / SIMD-tile), per view angle: "
              "single cone (sectors 1 x bands 1, the paper's map) and the binned map (the product's bins).", "",
              "| height map | angle | single cone: on vs off | binned: on vs off |", "|---|---|---|---|"]
    by = {(r["heightmap"], r["angle"], r["variant"]): r for r in twins}
    for name, angle in dict.fromkeys((r["heightmap"], r["angle"]) for r in twins):
        cells = [_change({v: by.get((name, angle, v)) for v in pair}, *pair) for pair in CONDITION_PAIRS]
        lines.append(f"| {name} | {angle:g}° | " + " | ".join(cells) + " |")
    return lines + [""]


def _variant_sections(rows: list[dict]) -> list[str]:
    lines = []
    present = dict.fromkeys(r["variant"] for r in _twins(rows))
    names = [v.name for v in VARIANTS if v.name in present]
    for name in dict.fromkeys(r["heightmap"] for r in rows):
        mine = [r for r in _twins(rows) if r["heightmap"] == name]
        if not mine:
            continue
        lines += [f"## {name} ({mine[0]['size']})", "",
                  "| angle | " + " | ".join(names + [c[0] for c in CHANGES]) + " |",
                  "|---|" + "---|" * (len(names) + len(CHANGES))]
        for angle in dict.fromkeys(r["angle"] for r in mine):
            cells, by = [], {r["variant"]: r for r in mine if r["angle"] == angle}
            for v in names:
                r = by.get(v)
                cells.append(f"{r['fetches_mean']:.2f} / {r['fetches_simd']:.2f}" if r else "-")
            cells += [_change(by, variant, base) for _, variant, base in CHANGES]
            lines.append(f"| {angle:g}° | " + " | ".join(cells) + " |")
        builds = {r["variant"]: r for r in mine}
        lines += ["", "build (s, cache included) and memory (MiB): " + "; ".join(
            f"{v}: {builds[v]['build_s']:.1f} s, {builds[v]['memory_mib']:.1f} MiB" for v in names if v in builds),
            ""]
        gpu = [r for r in rows if r["heightmap"] == name and r["tracer"] != "numpy twin"]
        if gpu:
            lines.append(f"GPU renderer ({gpu[0]['tracer']}), same views: " + "; ".join(
                f"{r['variant']} {r['angle']:g}° {r['fetches_mean']:.2f} / {r['fetches_simd']:.2f}" for r in gpu))
            lines.append("")
    return lines


#: Views at or beyond this angle are the grazing section's.
GRAZING = 85.0


def _grazing_section(rows: list[dict]) -> list[str]:
    graze = [r for r in rows if r["angle"] >= GRAZING and r["variant"] in (PLAIN, PRODUCT)]
    if not graze:
        return []
    lines = ["## Grazing views", "",
             f"Fetches (mean / SIMD-tile) and the pixels the tracer's cap stopped (capped), at {GRAZING:g}° and "
             f"beyond; rays past the refined map's {REFINED_MAX_ANGLE:g}° cone use its plain volume. The GPU rows "
             "are the product as it is; the twin models the sphere-step / cell-solve loop alone, so a GPU row below "
             "its twin is the product's own grazing finish at work.", "",
             "| height map | angle | map | tracer | fetches | capped |", "|---|---|---|---|---|---|"]
    for r in graze:
        lines.append(f"| {r['heightmap']} | {r['angle']:g}° | {r['variant']} | {r['tracer']} | "
                     f"{r['fetches_mean']:.2f} / {r['fetches_simd']:.2f} | {100 * r['capped']:.2f} % |")
    return lines + [""]


def _donnelly_section(rows: list[dict]) -> list[str]:
    if not rows:
        return []
    budgets = sorted({r["iterations"] for r in rows if r["regime"] == "fixed"})
    lines = ["## Donnelly's regime: fixed iterations, trilinear lookups, no finish", "",
             "A float64 numpy model of Donnelly's loop (`studies/refined_distance/donnelly.py`): from the surface "
             "plane, N steps of the trilinearly filtered stored distance, the point reached is the hit (no finish). "
             "Error: |uv reached - uv of the float64 exact first hit| in texels, p95 / max; passed: rays whose point "
             "lies past the exact hit (a trilinear blend of conservative voxels can step through the surface). "
             "Exact: the product's tracer (the twin; its fetches include the exact cell gathers).", "",
             "| height map | angle | map | " + " | ".join(f"N={n} p95 / max (passed)" for n in budgets) +
             " | exact: fetches (p95 / max) |", "|---|---|---|" + "---|" * (len(budgets) + 1)]
    keys = dict.fromkeys((r["heightmap"], r["angle"], r["variant"]) for r in rows)
    for key in keys:
        mine = {r["iterations"]: r for r in rows if (r["heightmap"], r["angle"], r["variant"]) == key}
        cells = [f"{mine[n]['error_p95']:.2f} / {mine[n]['error_max']:.2f} ({100 * mine[n]['passed']:.1f} %)"
                 if n in mine else "-" for n in budgets]
        exact = mine.get(None)
        cells.append(f"{exact['fetches_mean']:.1f} ({exact['error_p95']:.3f} / {exact['error_max']:.3f})"
                     if exact else "-")
        lines.append(f"| {key[0]} | {key[1]:g}° | {key[2]} | " + " | ".join(cells) + " |")
    return lines + [""]


def formats_markdown(built: list[dict], costs: list[dict]) -> list[str]:
    """ONE table: per map format, bytes per texel, build time (GPU path / CPU reference) per size, and the GPU
    renderer's fetches / SIMD-tile fetches / ms to the exact hit per angle (per height map of the costs)."""
    sizes = sorted({b["size"] for b in built})
    cost_keys = list(dict.fromkeys((c["heightmap"], c["angle"]) for c in costs))
    head = (["format", "bytes / texel"] + [f"build {n}² GPU / CPU (s)" for n in sizes] +
            [f"{m} {a:g}°: fetches / SIMD / ms" for m, a in cost_keys])
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for fmt in formats.FORMATS:
        mine = [b for b in built if b["format"] == fmt]
        if not mine:
            continue
        cells = [f"`{fmt}`", f"{mine[0]['bytes_per_texel']:.1f}"]
        for n in sizes:
            pair = []
            for backend in formats.BACKENDS:
                b = next((b for b in mine if b["size"] == n and b["backend"] == backend), None)
                pair.append("-" if b is None else f"{'~' if b['extrapolated'] else ''}{b['build_s']:.2f}")
            cells.append(" / ".join(pair))
        for m, a in cost_keys:
            c = next((c for c in costs if (c["heightmap"], c["angle"], c["format"]) == (m, a, fmt)), None)
            cells.append("-" if c is None else f"{c['fetches_mean']:.1f} / {c['fetches_simd']:.1f} / {c['ms']:.2f}")
        lines.append("| " + " | ".join(cells) + " |")
    return lines


def _formats_section(built: list[dict], costs: list[dict]) -> list[str]:
    if not built:
        return []
    settings = "; ".join(dict.fromkeys(f"`{b['format']}` {b['settings']}" for b in built if b["size"] ==
                                       max(x["size"] for x in built) and b["backend"] == "gpu"))
    return ["## Map formats: memory, build time, cost to the exact hit", "",
            "Bytes per height-map texel of the texture(s) the renderer uploads; build time uncached, GPU path / CPU "
            "reference (~: not run, extrapolated in proportion to the texels from the largest size measured within "
            "the suite's budget); fetches (mean / SIMD-tile 8x4) and median ms per frame of the format's technique "
            "in the GPU renderer (on a software adapter only the fetches and the ms ratios mean anything). "
            f"Settings at the largest size: {settings}.", "", *formats_markdown(built, costs), ""]
