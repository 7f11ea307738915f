"""``wgpuviewer refined-distance``: fetches per pixel of the distance tracer on every distance-map variant, on the
benchmark's full-screen views (wgpuviewer.bench.view), mean and SIMD-tile (``accuracy.simd_tile_cost``), with the
build time and memory of each map. Variants no technique binds are traced by the numpy twin of the tracer
(tracer.py); the two registered techniques also by the GPU renderer, side by side, as the check.
"""

from __future__ import annotations

import math
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from maptools.cache import cached_generate
from wgpuviewer.core.io import write_bytes
from wgpuviewer.harness import suite as harness_suite
from wgpuviewer.harness.header import Clock, Header
from wgpuviewer.harness.plots import MISSING, pyplot, save_png
from wgpuviewer.harness.table import Column, Table
from wgpuviewer.relief.accuracy import simd_tile_cost
from wgpuviewer.relief.maps import DISTANCE_SLICES, depth_range
from wgpuviewer.relief.techniques import REFINED_BANDS, REFINED_MAX_ANGLE, REFINED_SECTORS

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

    def bins(self) -> dict:
        """The tracer's view of the map: sectors, bands and max_angle (refined kind) or nothing (plain)."""
        if self.kind != "distance_refined":
            return {}
        return {k: self.options[k] for k in ("sectors", "bands", "max_angle")}


def _refined(sectors: int, bands: int, technique: str = "") -> Variant:
    name = "single cone" if sectors == bands == 1 else f"{sectors} sectors x {bands} bands"
    return Variant(name, "distance_refined", {"sectors": sectors, "bands": bands, "max_angle": REFINED_MAX_ANGLE},
                   technique)


VARIANTS = (
    Variant("plain before (maptools-2)", BEFORE, {}),
    Variant("plain K=1", "distance", {"subcells": 1}),
    Variant("plain K=4", "distance", {"subcells": 4}, "distance"),
    _refined(1, 1),
    _refined(8, 1),
    _refined(1, REFINED_BANDS),
    _refined(2, REFINED_BANDS),
    _refined(REFINED_SECTORS, REFINED_BANDS, "distance_refined"),
)
PRODUCT = VARIANTS[-1].name


@dataclass(frozen=True)
class Suite(harness_suite.Suite):
    heightmaps: tuple[str, ...]
    angles: tuple[float, ...]
    resolution: tuple[int, int]
    builtin_size: int


SUITES = harness_suite.suites(
    Suite("smoke", ("bricks", "wall"), (45.0, 80.0), (32, 16), 32),
    Suite("full", ("brick", "grass", "gravel", "bricks", "bumps", "ridges", "wall"),
          (0.0, 30.0, 45.0, 60.0, 75.0, 80.0), (256, 144), 256),
)

#: results.csv: one row per height map x variant x angle x tracer (the numpy twin; the GPU renderer where a
#: technique renders the variant).
TABLE = Table("refined-distance results", (
    Column("heightmap", str), Column("size", str, "texels, WxH"), Column("angle", float, "degrees"),
    Column("variant", str), Column("tracer", str), Column("fetches_mean", float, "fetches per pixel"),
    Column("fetches_simd", float, "fetches per SIMD tile of 8x4 pixels"), Column("capped", float, "of the pixels"),
    Column("build_s", float, "seconds, cache included"), Column("memory_mib", float, "MiB"),
))

#: The report's title (harness.header).
TITLE = "Distance-map variants: fetches per pixel (mean / SIMD-tile 8x4)"


def _build(variant: Variant, height: np.ndarray, height_scale: float) -> tuple[np.ndarray, float]:
    t0 = time.perf_counter()
    if variant.kind == BEFORE:
        out = plain_before(height, slices=DISTANCE_SLICES, height_scale=height_scale)
        return out, time.perf_counter() - t0
    out = cached_generate(variant.kind, height, backend="auto", slices=DISTANCE_SLICES, height_scale=height_scale,
                          **variant.options)
    return out, time.perf_counter() - t0


def run(suite_name: str, out: Path, heightmaps=None, angles=None, backend: str | None = None,
        progress: bool = True, command: str = "wgpuviewer refined-distance") -> list[dict]:
    """Measure every variant of ``SUITES[suite_name]``; write ``out``/results.csv and report.md; return the rows."""
    from tqdm import tqdm

    from wgpuviewer.bench.run import REAL_MAPS, skimage_available
    from wgpuviewer.bench.view import HEIGHT_SCALE, load_heightmap, make_view
    from wgpuviewer.core.gpu import get_gpu
    from wgpuviewer.relief.renderer import DrawConfig, Renderer

    suite = harness_suite.pick(SUITES, suite_name)
    clock = Clock()
    maps = tuple(heightmaps or suite.heightmaps)
    if heightmaps is None and not skimage_available():
        maps = tuple(m for m in maps if m not in REAL_MAPS)
    gpu = get_gpu(backend, quiet=True)
    rows: list[dict] = []
    out = Path(out)  # checked and made by the command first (harness.study.run_study)
    with tempfile.TemporaryDirectory(prefix="wgpuviewer-refined-") as workdir, \
            tqdm(total=len(maps) * len(VARIANTS), desc="refined-distance", unit="map", disable=not progress) as bar:
        for name in maps:
            heightmap = load_heightmap(name, suite.builtin_size, Path(workdir))
            depth = 1.0 - heightmap.height.astype(np.float64)
            depth_min = depth_range(depth, gpu.depth_format)[0]  # where the GPU tracer starts
            views = [make_view(heightmap, a, suite.resolution) for a in (angles or suite.angles)]
            for variant in VARIANTS:
                volumes, seconds = _build(variant, heightmap.height, HEIGHT_SCALE)
                for view in views:
                    covered = np.ones(view.uv0.shape[:2], bool)
                    got = trace(depth, volumes, view.uv0.reshape(-1, 2), view.v_ts.reshape(-1, 3), HEIGHT_SCALE,
                                depth_min=depth_min, **variant.bins())
                    rows.append(_row(heightmap, view, variant, "numpy twin", got.fetches.reshape(covered.shape),
                                     covered, got.capped, seconds, volumes))
                    if variant.technique:
                        image = Renderer(view.scene, gpu).render(DrawConfig.of(variant.technique), suite.resolution)
                        raw = image.data[:, :, 3]
                        fetches = np.where(raw < 0, -raw - 1.0, raw)
                        rows.append(_row(heightmap, view, variant, f"GPU ({gpu.summary})", fetches, image.covered,
                                         raw[image.covered] < 0, seconds, volumes))
                bar.update()
            _write(out, rows, clock.header(TITLE, command, gpu.summary, suite.name))
    return rows


def _row(heightmap, view, variant, tracer, fetches, covered, capped, seconds, volumes) -> dict:
    return {"heightmap": heightmap.name, "size": f"{heightmap.size[0]}x{heightmap.size[1]}", "angle": view.angle,
            "variant": variant.name, "tracer": tracer,
            "fetches_mean": float(np.mean(fetches[covered])), "fetches_simd": simd_tile_cost(fetches, covered=covered),
            "capped": float(np.mean(capped)), "build_s": seconds, "memory_mib": volumes.nbytes / 2**20}


def _write(out: Path, rows: list[dict], header: Header) -> None:
    """results.csv, the plot and report.md of the rows so far (rewritten after each height map)."""
    TABLE.write(out / "results.csv", rows)
    plotted = plot(rows, out / PLOT)
    write_bytes(out / "report.md", report(rows, header, plotted).encode())


#: The picture of the report: fetches per pixel against the view angle, one panel per height map.
PLOT = "fetches_vs_angle.png"


def plot(rows: list[dict], path: Path) -> bool:
    """Mean fetches per pixel (solid) and SIMD-tile fetches (dotted) against the view angle, one line per variant
    and one panel per height map (numpy-twin rows). False when matplotlib is missing (the tables still stand)."""
    with pyplot() as plt:
        if plt is None:
            return False
        _draw(plt, rows, path)
    return True


def _draw(plt, rows: list[dict], path: Path) -> None:
    twins = [r for r in rows if r["tracer"] == "numpy twin"]
    maps = list(dict.fromkeys(r["heightmap"] for r in twins))
    cols = min(4, len(maps)) or 1
    panel_rows = math.ceil(len(maps) / cols) or 1
    fig, axes = plt.subplots(panel_rows, cols, figsize=(3.6 * cols, 3.0 * panel_rows), squeeze=False)
    for ax, name in zip(axes.ravel(), maps):
        for i, variant in enumerate(v.name for v in VARIANTS):
            mine = sorted((r["angle"], r["fetches_mean"], r["fetches_simd"])
                          for r in twins if r["heightmap"] == name and r["variant"] == variant)
            if not mine:
                continue
            angles, mean, simd = zip(*mine)
            color = plt.cm.tab10(i % 10)
            ax.plot(angles, mean, "-o", ms=2.5, lw=1.2 if variant != PRODUCT else 2.2, color=color, label=variant)
            ax.plot(angles, simd, ":", lw=0.8, color=color)
        ax.set_title(f"{name} ({next(r['size'] for r in twins if r['heightmap'] == name)})", fontsize=9)
        ax.set_xlabel("view angle at the frame centre (deg)", fontsize=7)
        ax.set_ylabel("fetches per pixel", fontsize=7)
        ax.tick_params(labelsize=7)
        ax.grid()
    for ax in axes.ravel()[len(maps):]:
        ax.axis("off")
    handles, labels = axes.ravel()[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=min(4, len(labels)), fontsize=7, frameon=False)
    fig.suptitle("Distance-map variants: every fetch to the exact hit (solid: mean, dotted: SIMD-tile 8x4)", fontsize=9)
    fig.tight_layout(rect=(0, 0.08, 1, 0.96))
    save_png(fig, path, tight=False)


#: The report's change columns: (label, variant, against which variant).
CHANGES = (("K=4 vs before", "plain K=4", VARIANTS[0].name), ("product vs before", PRODUCT, VARIANTS[0].name),
           ("product vs K=4", PRODUCT, "plain K=4"))


def _change(by: dict, variant: str, base: str) -> str:
    a, b = by.get(variant), by.get(base)
    if not (a and b):
        return "-"
    return (f"{100 * (a['fetches_mean'] / b['fetches_mean'] - 1):+.0f} % / "
            f"{100 * (a['fetches_simd'] / b['fetches_simd'] - 1):+.0f} %")


def report(rows: list[dict], header: Header, plotted: bool) -> str:
    """Markdown: per height map, fetches per pixel mean / SIMD-tile by angle (rows) and variant (columns), the changes
    of the box-exact plain map and of the product's refined map against the maptools-2 map and against each other,
    build times and memory."""
    lines = [*header.lines(), "",
             "Every fetch to the final hit (volume fetches and exact-cell gathers), the same tracer for every map. "
             "Changes: mean / SIMD-tile. " + (f"Plot: [{PLOT}]({PLOT})." if plotted else MISSING), ""]
    variants = [v.name for v in VARIANTS]
    for name in dict.fromkeys(r["heightmap"] for r in rows):
        mine = [r for r in rows if r["heightmap"] == name and r["tracer"] == "numpy twin"]
        if not mine:
            continue
        lines += [f"## {name} ({mine[0]['size']})", "",
                  "| angle | " + " | ".join(variants + [c[0] for c in CHANGES]) + " |",
                  "|---|" + "---|" * (len(variants) + len(CHANGES))]
        for angle in dict.fromkeys(r["angle"] for r in mine):
            cells, by = [], {r["variant"]: r for r in mine if r["angle"] == angle}
            for v in variants:
                r = by.get(v)
                cells.append(f"{r['fetches_mean']:.2f} / {r['fetches_simd']:.2f}" if r else "-")
            cells += [_change(by, variant, base) for _, variant, base in CHANGES]
            lines.append(f"| {angle:g}° | " + " | ".join(cells) + " |")
        builds = {r["variant"]: r for r in mine}
        lines += ["", "build (s, cache included) and memory (MiB): " + "; ".join(
            f"{v}: {builds[v]['build_s']:.1f} s, {builds[v]['memory_mib']:.1f} MiB" for v in variants if v in builds),
            ""]
        gpu = [r for r in rows if r["heightmap"] == name and r["tracer"] != "numpy twin"]
        if gpu:
            lines.append(f"GPU renderer ({gpu[0]['tracer']}), same views: " + "; ".join(
                f"{r['variant']} {r['angle']:g}° {r['fetches_mean']:.2f} / {r['fetches_simd']:.2f}" for r in gpu))
            lines.append("")
    return "\n".join(lines) + "\n"
