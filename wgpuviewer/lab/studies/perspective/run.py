"""``wgpuviewer perspective --out DIR``: every method's speed and texture-coordinate error against float64.

Every configuration's texel density gives its frame's middle pixel a footprint of ``FOOTPRINT`` texels
(``geometry.at_footprint``), so errors in texels and in screen pixels stay comparable across span lengths and
tilts. Sweeps (each configuration: ``instances`` geometries whose texel density differs by a fraction of a percent,
so that the float32 rounding pattern is sampled rather than one fixed pattern; errors pooled over them):

- ``span_length``: span (frame) lengths at tilt ``SWEEP_TILT``, offset 0;
- ``tile``: a ``sweep_span`` frame cut into spans of 8 to 64 pixels, each from its own exact start (how tile and
  GPU rasterisers walk a row), at the suite's ``tile_tilts``;
- ``tilt``: far-end angles up to nearly edge-on and past the horizon, at the suite's ``sweep_span``;
- ``magnitude``: texel offsets (heavy tiling) at ``sweep_span`` and ``SWEEP_TILT``;
- ``speed``: whole frames (and few long spans) timed as compiled CPU loops (``compiled``: scalar and SIMD builds,
  round robin, ratio to ``direct`` in the same repeat), on the GPU adapter (timestamp queries or wall clock,
  round robin, ratio to ``direct`` in the same run) and as numpy code, with their errors and operation counts;
- ``speed_tile``: the first speed frame cut into spans of ``tile_timing`` pixels, timed as compiled loops (the
  cost of the tile regime, where each span's setup is shared by few pixels);

plus the error along the span at ``ALONG_SPAN`` pixels, a picture of where the incremental drift lands on a long
grazing quad, and the relief tie-back (``tieback``). Each method's float32 kernel and compiled loops (both builds)
are compared with its numpy twin in every configuration (``gpu_max_ulp``, ``gpu_flag_mismatch``, ``cpu_max_ulp``,
``cpu_flag_mismatch``).
"""

from __future__ import annotations

import platform
import sys
import time
from collections import Counter
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from wgpuviewer.core.io import write_bytes
from wgpuviewer.lab.harness import suite as harness_suite
from wgpuviewer.lab.harness.header import Clock
from wgpuviewer.lab.harness.table import Column, Table, columns

from . import threads_report, tieback
from .geometry import Quad, Reference, Setup, Spans, at_footprint, build, reference, tiles_of
from .methods import METHODS, Result, evaluate, ops_per_texel
from .threaded import THREADS_TABLE

SWEEP_TILT = 80.0  # degrees at the far end of the span: a grazing wall, still well before edge-on
FOOTPRINT = 1.0  # texels per pixel at every configuration's middle pixel
HEATMAP_TILT = 85.0
ALONG_SPAN = 8192
ALONG_BINS = 32
HARDWARE = "hardware"
DIRECT = "direct"


@dataclass(frozen=True)
class Suite(harness_suite.Suite):
    span_lengths: tuple[int, ...]
    tilts: tuple[float, ...]
    offsets: tuple[float, ...]
    rows: int  # spans per geometry
    instances: int  # geometries per configuration
    sweep_span: int  # span length of the tilt and magnitude sweeps, frame width of the tile sweep
    tile_widths: tuple[int, ...]  # divisors of sweep_span
    tile_tilts: tuple[float, ...]
    speed_frames: tuple[tuple[int, int], ...]  # (span length, spans)
    gpu_repeats: int
    cpu_repeats: int  # numpy
    compiled_repeats: int
    compiled_sample_s: float  # seconds each compiled sample lasts at least (calls back to back)
    tile_timing: int  # the tile width the compiled loops are timed on (a divisor of the first speed frame's width)
    heatmap_frame: tuple[int, int]
    relief_techniques: tuple[str, ...]
    relief_magnitudes: tuple[float, ...]
    relief_rays: int
    relief_texels: int


SUITES = harness_suite.suites(
    Suite("smoke", (256, 1920, 3840, 8192), (45.0, 80.0, 89.9, 95.0), (0.0, 1e4, 1e6), rows=4, instances=2,
                   sweep_span=1920, tile_widths=(16, 64), tile_tilts=(80.0,), speed_frames=((1920, 128), (8192, 16)),
                   gpu_repeats=7, cpu_repeats=2, compiled_repeats=5, compiled_sample_s=0.002, tile_timing=16,
                   heatmap_frame=(480, 270), relief_techniques=("pom", "maxmip"),
                   relief_magnitudes=(0.0, 1e3, 1e5, 1e7), relief_rays=256, relief_texels=64),
    # Powers of two and their neighbours, and lengths between: the drift depends on the increment's low bits.
    Suite("full", (64, 128, 256, 512, 1000, 1024, 1366, 1920, 2048, 2560, 3000, 3840, 4095, 4096, 5000,
                   6000, 7680, 8192, 10000, 12000, 16383, 16384),
                  (30.0, 45.0, 60.0, 70.0, 75.0, 80.0, 85.0, 87.0, 89.0, 89.5, 89.9, 90.0, 95.0),
                  (0.0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7), rows=16, instances=8, sweep_span=3840,
                  tile_widths=(8, 16, 32, 64), tile_tilts=(80.0, 89.9), speed_frames=((3840, 2160), (8192, 64)),
                  gpu_repeats=15, cpu_repeats=3, compiled_repeats=25, compiled_sample_s=0.03, tile_timing=16,
                  heatmap_frame=(1920, 1080), relief_techniques=("pom", "relief", "maxmip", "cone", "distance"),
                  relief_magnitudes=(0.0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7), relief_rays=4096, relief_texels=128),
)

def _timed(name: str, unit: str, ratio_unit: str = "x direct") -> tuple[Column, ...]:
    """A timing's columns: ``name`` (PREFIX_ns or PREFIX_ms, the median), PREFIX_ratio and PREFIX_spread."""
    prefix = name.rpartition("_")[0]
    return (Column(name, float, unit), Column(f"{prefix}_ratio", float, ratio_unit),
            Column(f"{prefix}_spread", float, "interquartile range / median"))


#: results.csv: one row per sweep configuration x method x precision. A cell that does not apply to the row (the
#: GPU time outside the speed sweep, the kernel check of a method's second precision) is empty.
TABLE = Table("perspective results", (
    Column("suite", str), Column("sweep", str), Column("method", str), Column("family", str),
    Column("precision", str), Column("span_length", int, "pixels"), Column("spans", int),
    Column("tilt_deg", float, "degrees at the span's far end"), Column("offset_texels", float, "texels"),
    Column("coord_max_texels", float, "texels"), Column("footprint_texels", float, "texels per pixel, median"),
    *columns(float, "screen pixels", "max_err_px", "p99_err_px", "mean_err_px"),
    *columns(float, "texels", "max_err", "p99_err", "mean_err"), Column("flagged_fraction", float, "of the pixels"),
    Column("undetected", int, "pixels"), Column("exact_per_pixel", float, "divided evaluations per pixel"),
    *(c for side in ("gpu", "cpu") for c in (Column(f"{side}_max_ulp", int, "float32 ulp"),
                                             Column(f"{side}_flag_mismatch", int, "pixels"))),
    *_timed("scalar_ns", "ns per texel, median"), *_timed("simd_ns", "ns per texel, median", "x direct (SIMD build)"),
    Column("simd_vectorised", str, "what LLVM made of the loop"), *_timed("gpu_ms", "ms, median"),
    *_timed("numpy_ms", "ms, median")[:2],
    *(Column(f"{kind}_per_texel", float, "operations") for kind in ("adds", "muls", "divs", "sqrts", "guards",
                                                                    "int_adds")),
    *(Column(f"fma_{kind}_per_texel", float, "operations with fused multiply-add") for kind in ("adds", "muls",
                                                                                               "fmas")),
    Column("ops_per_span", float, "operations"), Column("paper_adds", int), Column("paper_muls", int),
    Column("paper_divs", int), Column("timer", str), Column("adapter", str),
))
COLUMNS = TABLE.names
#: along_span.csv: the error in bins along one long span.
ALONG_TABLE = Table("perspective along-span errors", (
    Column("method", str), Column("precision", str), Column("span_length", int, "pixels"),
    Column("n_start", int, "pixels"), Column("n_end", int, "pixels"), Column("max_err_px", float, "screen pixels"),
    Column("mean_err_px", float, "screen pixels"), Column("max_err", float, "texels"), Column("mean_err", float, "texels"),
))
#: tieback.csv: relief techniques' hit uv at large texture coordinates (tieback.py).
TIEBACK_TABLE = Table("perspective relief tie-back", (
    Column("technique", str), Column("magnitude_uv", float, "UV units"), Column("variant", str),
    Column("texels", int), Column("rays", int), Column("angle_deg", float, "degrees"),
    Column("input_spacing_texels", float, "texels"), Column("max_err", float, "texels"),
    Column("p99_err", float, "texels"), Column("mean_err", float, "texels"),
    Column("capped_fraction", float, "of the rays"),
))


def configured(setup: Setup) -> Setup:
    """``setup`` at the study's texel density: ``FOOTPRINT`` texels per pixel at its middle pixel."""
    return at_footprint(setup, FOOTPRINT)


def instances(setup: Setup, count: int) -> list[Setup]:
    """``count`` geometries like ``setup``, texel density apart by 0.37 % steps (a different rounding pattern each)."""
    return [replace(setup, texels_per_unit=setup.texels_per_unit * (1.0 + 0.0037 * i)) for i in range(count)]


def variants() -> list[tuple[str, str]]:
    """(method, precision) of every evaluation, registry order."""
    return [(m.name, p) for m in METHODS.values() for p in m.precisions]


def ulp_difference(a: np.ndarray, b: np.ndarray) -> int:
    """Largest distance in float32 units in the last place between two float32 arrays of the same shape."""
    ia, ib = (np.ascontiguousarray(x, np.float32).view(np.int32).astype(np.int64) for x in (a, b))
    ia, ib = (np.where(i < 0, np.int64(-(2**31)) - i, i) for i in (ia, ib))  # monotonic integer order
    return int(np.abs(ia - ib).max()) if ia.size else 0


def twin_difference(got: Result, want: Result) -> tuple[int, int]:
    """(largest float32 ulp difference of u and v, pixels whose flags differ) of two results of one method."""
    return (max(ulp_difference(got.u, want.u), ulp_difference(got.v, want.v)),
            int((got.flagged != want.flagged).sum()))


@dataclass
class Pooled:
    """Errors of one method over a configuration's geometries."""

    errors: list[np.ndarray] = field(default_factory=list)  # texels, valid and unflagged pixels
    in_pixels: list[np.ndarray] = field(default_factory=list)  # the same errors over each pixel's footprint
    footprints: list[np.ndarray] = field(default_factory=list)  # texels per pixel of the valid pixels
    flagged: int = 0
    undetected: int = 0  # the reference says undefined, the method did not flag it
    pixels: int = 0
    exact: int | None = 0  # divided evaluations; None once a result did not count them
    per_pixel: list[tuple[np.ndarray, np.ndarray]] = field(default_factory=list)  # (R, L) texels and pixels, NaN
    # where not compared (along-span)
    tally: Counter = field(default_factory=Counter)  # operations (Arith.tally), when counted per configuration
    fused: Counter = field(default_factory=Counter)  # the same with fused multiply-adds (Arith.fused)

    def add(self, ref: Reference, result: Result, keep_per_pixel: bool = False) -> None:
        ok = ref.valid & ~result.flagged
        err = np.hypot(result.u.astype(np.float64) - ref.u, result.v.astype(np.float64) - ref.v)
        self.errors.append(err[ok])
        self.in_pixels.append(err[ok] / ref.footprint[ok])
        self.footprints.append(ref.footprint[ref.valid])
        self.flagged += int(result.flagged.sum())
        self.undetected += int((~ref.valid & ~result.flagged).sum())
        self.pixels += result.flagged.size
        self.exact = None if self.exact is None or result.exact is None else self.exact + result.exact
        if keep_per_pixel:
            self.per_pixel.append((np.where(ok, err, np.nan), np.where(ok, err / ref.footprint, np.nan)))

    def values(self) -> dict:
        e = np.concatenate(self.errors) if self.errors else np.empty(0)
        px = np.concatenate(self.in_pixels) if self.in_pixels else np.empty(0)
        fp = np.concatenate(self.footprints) if self.footprints else np.empty(0)
        nan = float("nan")

        def stats(x: np.ndarray, suffix: str = "") -> dict:
            return {f"max_err{suffix}": float(x.max()) if x.size else nan,
                    f"p99_err{suffix}": float(np.percentile(x, 99)) if x.size else nan,
                    f"mean_err{suffix}": float(x.mean()) if x.size else nan}

        return {
            **stats(e), **stats(px, "_px"), "footprint_texels": float(np.median(fp)) if fp.size else nan,
            "flagged_fraction": self.flagged / max(self.pixels, 1), "undetected": self.undetected,
            "exact_per_pixel": None if self.exact is None else self.exact / max(self.pixels, 1),
        }

    def op_counts(self) -> dict:
        """Operations per texel counted on this configuration (``Method.ops_vary``)."""
        per = max(self.pixels, 1)
        return {**{f"{kind}s_per_texel": self.tally[kind] / per for kind in ("add", "mul", "div", "sqrt", "guard")},
                "int_adds_per_texel": self.tally["int_add"] / per,
                **{f"fma_{kind}s_per_texel": self.fused[kind] / per for kind in ("add", "mul", "fma")}}


class Measurements:
    """One run's measurements: the device and kernels, the compiled loops, the rows so far, the per-method
    operation counts."""

    def __init__(self, suite: Suite, backend: str | None):
        from wgpuviewer.core.gpu import get_gpu

        from .compiled import BUILDS
        from .compiled import build as compiled_build
        from .kernels import kernels_for

        self.suite = suite
        self.gpu = get_gpu(backend, quiet=True)
        self.kernels = kernels_for(self.gpu)
        self.builds = {name: compiled_build(name) for name in BUILDS}
        self.rows: list[dict] = []
        self.along: list[dict] = []
        self.ops = {(name, p): (ops_per_texel(name, p), ops_per_texel(name, p, fused=True)) for name, p in variants()}

    def compile(self) -> None:
        """Every method's compiled loops, both builds (before any is timed)."""
        for loops in self.builds.values():
            loops.compile(METHODS)

    def base(self, sweep: str, method: str, precision: str, setup: Setup, spans: int, length: int | None = None) -> dict:
        """A row's identity and its method's operation counts; ``length``: the spans' (default the frame width)."""
        m = METHODS.get(method)
        row = TABLE.blank()
        row.update({
            "suite": self.suite.name, "sweep": sweep, "method": method, "family": m.family if m else HARDWARE,
            "precision": precision, "span_length": length or setup.span_length,
            "spans": spans, "tilt_deg": setup.tilt, "offset_texels": setup.offset, "adapter": self.gpu.summary,
        })
        if m:
            ops, fused = self.ops[(method, precision)]
            row.update({f"{kind}s_per_texel": ops.get(kind, (0.0, 0.0))[0]
                        for kind in ("add", "mul", "div", "sqrt", "guard")})
            row["int_adds_per_texel"] = ops.get("int_add", (0.0, 0.0))[0]
            row.update({f"fma_{kind}s_per_texel": fused.get(kind, (0.0, 0.0))[0] for kind in ("add", "mul", "fma")})
            row["ops_per_span"] = sum(per_span for _, per_span in ops.values())
            if m.paper_ops:
                row["paper_adds"], row["paper_muls"], row["paper_divs"] = m.paper_ops
        return row

    def check_compiled(self, row: dict, name: str, quad: Quad, spans: Spans, want: Result) -> None:
        """The compiled loops of both builds against the numpy twin ``want`` (the method's first precision)."""
        differences = [twin_difference(b.evaluate(name, METHODS[name].precisions[0], quad.coefficients, spans), want)
                       for b in self.builds.values()]
        row["cpu_max_ulp"] = max(d[0] for d in differences)
        row["cpu_flag_mismatch"] = max(d[1] for d in differences)

    def configuration(self, sweep: str, setup: Setup, count: int, along: bool = False,
                      tile: int | None = None) -> list[dict]:
        """Error rows of every method (and the rasteriser) on ``count`` geometries like ``setup``: on each frame's
        rows, or on its tiles of ``tile`` pixels (``geometry.tiles_of``; the rasteriser draws frames only)."""
        quads: list[Quad] = [build(s) for s in instances(configured(setup), count)]
        spans = quads[0].spans if tile is None else tiles_of(quads[0].frame, tile)
        refs = [reference(q.coefficients, spans) for q in quads]
        coord = max(float(max(np.abs(r.u[r.valid]).max(initial=0), np.abs(r.v[r.valid]).max(initial=0))) for r in refs)
        total = spans.count * len(quads)
        rows = []
        for name, precision in variants():
            method = METHODS[name]
            pooled = Pooled()
            row = self.base(sweep, name, precision, setup, total, spans.length)
            for i, (quad, ref) in enumerate(zip(quads, refs)):
                result, ar = evaluate(name, precision, quad.coefficients, spans)
                pooled.add(ref, result, keep_per_pixel=along)
                pooled.tally.update(ar.tally)
                pooled.fused.update(ar.fused)
                if i == 0 and precision == method.precisions[0]:  # the kernel's and the compiled loops' twin
                    if method.on_gpu:
                        gpu = self.kernels.run(name, quad.coefficients, spans)
                        row["gpu_max_ulp"], row["gpu_flag_mismatch"] = twin_difference(gpu, result)
                    self.check_compiled(row, name, quad, spans, result)
            row.update(pooled.values(), coord_max_texels=coord)
            if method.ops_vary:
                row.update(pooled.op_counts())
            rows.append(row)
            if along:
                self.add_along(name, precision, setup.span_length, pooled)
        if tile is None and not quads[0].horizon:  # the rasteriser draws finite quads only
            from .hardware import hardware_uv

            pooled = Pooled()
            for quad, ref in zip(quads, refs):
                pooled.add(ref, hardware_uv(quad, self.gpu), keep_per_pixel=along)
            rows.append({**self.base(sweep, HARDWARE, "float32", setup, total), **pooled.values(),
                         "coord_max_texels": coord})
            if along:
                self.add_along(HARDWARE, "float32", setup.span_length, pooled)
        return rows

    def add_along(self, method: str, precision: str, length: int, pooled: Pooled) -> None:
        texels = np.concatenate([t for t, _ in pooled.per_pixel], axis=0)
        pixels = np.concatenate([p for _, p in pooled.per_pixel], axis=0)
        edges = np.linspace(0, length, ALONG_BINS + 1).astype(int)
        nan = float("nan")
        for lo, hi in zip(edges[:-1], edges[1:]):
            seen = np.isfinite(texels[:, lo:hi]).any()
            row = {"method": method, "precision": precision, "span_length": length, "n_start": int(lo),
                   "n_end": int(hi)}
            for suffix, err in (("", texels[:, lo:hi]), ("_px", pixels[:, lo:hi])):
                row[f"max_err{suffix}"] = float(np.nanmax(err)) if seen else nan
                row[f"mean_err{suffix}"] = float(np.nanmean(err)) if seen else nan
            self.along.append(row)

    def speed(self, frame: tuple[int, int]) -> list[dict]:
        """Compiled CPU, GPU and numpy time of every method's first precision on one frame, with its errors there.

        The compiled loops of each build take turns in one run (``compiled.time_loops``); all kernels and the
        rasteriser's pass take turns in another (core.pass_timing): timestamp queries on hardware adapters, wall clock
        net of an empty pass on software ones (whose compute timestamps are unreliable)."""
        from wgpuviewer.core.pass_timing import time_passes

        from .compiled import time_loops
        from .hardware import frame_recorder, hardware_uv, renderer_for

        setup = Setup(span_length=frame[0], rows=frame[1], tilt=SWEEP_TILT)
        quad = build(configured(setup))
        ref = reference(quad.coefficients, quad.spans)
        names = list(METHODS)
        compiled = {b: time_loops(loops, names, quad.coefficients, quad.spans, self.suite.compiled_repeats,
                                  self.suite.compiled_sample_s) for b, loops in self.builds.items()}
        on_gpu = [n for n in names if METHODS[n].on_gpu]
        outputs = self.kernels.outputs(quad.spans)
        recorders = [self.kernels.prepare(n, quad.coefficients, quad.spans, outputs).record for n in on_gpu]
        renderer = renderer_for(quad, self.gpu)
        recorders.append(frame_recorder(quad, renderer))
        timings = time_passes(self.gpu.device, recorders, self.suite.gpu_repeats, warmup=2,
                              timestamps="timestamp-query" in self.gpu.features and not self.gpu.software)
        gpu_ms = dict(zip([*on_gpu, HARDWARE], timings.median_ms))
        # interquartile range of the single passes over their median: how far one pass's time is to be trusted
        spread = {n: float(np.subtract(*np.percentile(t, [75, 25])) / max(np.median(t), 1e-12))
                  for n, t in zip([*on_gpu, HARDWARE], timings.samples_ms)}
        rows = []
        numpy_ms = {}
        for name in names:
            method = METHODS[name]
            precision = method.precisions[0]
            times = []
            for _ in range(self.suite.cpu_repeats):
                start = time.perf_counter()
                result, ar = evaluate(name, precision, quad.coefficients, quad.spans)
                times.append((time.perf_counter() - start) * 1e3)
            numpy_ms[name] = float(np.median(times))
            pooled = Pooled()
            pooled.add(ref, result)
            pooled.tally.update(ar.tally)
            pooled.fused.update(ar.fused)
            row = {**self.base("speed", name, precision, setup, quad.spans.count), **pooled.values(),
                   "numpy_ms": numpy_ms[name], "numpy_ratio": numpy_ms[name] / numpy_ms[DIRECT]}
            if method.ops_vary:
                row.update(pooled.op_counts())
            self.check_compiled(row, name, quad, quad.spans, result)
            for b, timing in compiled.items():
                row.update({f"{b}_ns": timing.median(name), f"{b}_ratio": timing.ratio(name),
                            f"{b}_spread": timing.spread(name)})
            row["simd_vectorised"] = self.builds["simd"].vectorisation(name)
            if method.on_gpu:
                ms = gpu_ms[name]
                row.update(gpu_ms=ms, gpu_ratio=ms / gpu_ms[DIRECT] if gpu_ms[DIRECT] > 0 else float("nan"),
                           gpu_spread=spread[name], timer=timings.timer)
            rows.append(row)
        pooled = Pooled()
        pooled.add(ref, hardware_uv(quad, self.gpu, renderer))
        ms = gpu_ms[HARDWARE]
        rows.append({**self.base("speed", HARDWARE, "float32", setup, quad.spans.count), **pooled.values(),
                     "gpu_ms": ms, "gpu_ratio": ms / gpu_ms[DIRECT] if gpu_ms[DIRECT] > 0 else float("nan"),
                     "gpu_spread": spread[HARDWARE], "timer": timings.timer})
        return rows

    def tile_speed(self, frame: tuple[int, int], width: int) -> list[dict]:
        """Compiled time of every method on ``frame`` cut into spans of ``width`` pixels, with its errors there (of
        the numpy twin, which both builds are checked against)."""
        from .compiled import time_loops

        setup = Setup(span_length=frame[0], rows=frame[1], tilt=SWEEP_TILT)
        quad = build(configured(setup))
        spans = tiles_of(quad.frame, width)
        ref = reference(quad.coefficients, spans)
        names = list(METHODS)
        compiled = {b: time_loops(loops, names, quad.coefficients, spans, self.suite.compiled_repeats,
                                  self.suite.compiled_sample_s) for b, loops in self.builds.items()}
        rows = []
        for name in names:
            method = METHODS[name]
            result, ar = evaluate(name, method.precisions[0], quad.coefficients, spans)
            pooled = Pooled()
            pooled.add(ref, result)
            pooled.tally.update(ar.tally)
            pooled.fused.update(ar.fused)
            row = {**self.base("speed_tile", name, method.precisions[0], setup, spans.count, width), **pooled.values()}
            if method.ops_vary:
                row.update(pooled.op_counts())
            self.check_compiled(row, name, quad, spans, result)
            for b, timing in compiled.items():
                row.update({f"{b}_ns": timing.median(name), f"{b}_ratio": timing.ratio(name),
                            f"{b}_spread": timing.spread(name)})
            row["simd_vectorised"] = self.builds["simd"].vectorisation(name)
            rows.append(row)
        return rows

    def heatmap(self) -> dict:
        """Per-pixel errors (screen pixels) of the float32 incremental and direct forms on a long grazing quad, and
        its uv."""
        w, h = self.suite.heatmap_frame
        quad = build(configured(Setup(span_length=w, rows=h, tilt=HEATMAP_TILT)))
        ref = reference(quad.coefficients, quad.spans)
        out = {"setup": quad.setup, "reference": ref}
        for name in ("incremental", DIRECT):
            result, _ = evaluate(name, "float32", quad.coefficients, quad.spans)
            err = np.hypot(result.u - ref.u, result.v - ref.v) / ref.footprint
            out[name] = np.where(ref.valid & ~result.flagged, err, np.nan)
        return out


def run(suite_name: str, out: Path, backend: str | None = None, progress: bool = True,
        command: str = "wgpuviewer perspective") -> list[dict]:
    """Run the study; write results.csv, along_span.csv, tieback.csv, report.md and the plots into ``out`` (the
    command checks and makes it first: ``harness.study.run_study``)."""
    from tqdm import tqdm

    from .compiled import cpu_model, numba_module
    from .plots import write_plots
    from .report import TITLE, report_text

    suite = harness_suite.pick(SUITES, suite_name)
    out = Path(out)
    clock = Clock()
    study = Measurements(suite, backend)
    configs = ([("span_length", Setup(span_length=n, rows=suite.rows, tilt=SWEEP_TILT), None)
                for n in suite.span_lengths]
               + [("tile", Setup(span_length=suite.sweep_span, rows=suite.rows, tilt=t), w)
                  for t in suite.tile_tilts for w in suite.tile_widths]
               + [("tilt", Setup(span_length=suite.sweep_span, rows=suite.rows, tilt=t), None) for t in suite.tilts]
               + [("magnitude", Setup(span_length=suite.sweep_span, rows=suite.rows, tilt=SWEEP_TILT, offset=o), None)
                  for o in suite.offsets])
    relief_steps = len(suite.relief_techniques) * len(suite.relief_magnitudes) * len(tieback.VARIANTS)
    with tqdm(total=len(configs) + len(suite.speed_frames) + relief_steps + 3, desc="perspective", unit="step",
              file=sys.stderr, disable=not progress) as bar:
        bar.set_postfix_str("compiling the CPU loops")
        study.compile()
        bar.update()
        for sweep, setup, tile in configs:
            bar.set_postfix_str(f"{sweep} L={tile or setup.span_length} tilt={setup.tilt:g} offset={setup.offset:g}")
            study.rows += study.configuration(sweep, setup, suite.instances, tile=tile,
                                              along=sweep == "span_length" and setup.span_length == ALONG_SPAN)
            bar.update()
        for frame in suite.speed_frames:
            bar.set_postfix_str(f"speed {frame[0]}x{frame[1]}")
            study.rows += study.speed(frame)
            bar.update()
        bar.set_postfix_str(f"speed {suite.tile_timing}-pixel tiles")
        study.rows += study.tile_speed(suite.speed_frames[0], suite.tile_timing)
        bar.update()
        first = suite.speed_frames[0]  # timed on threads after the single-threaded timings, before the heat map
        threads = threads_report.measure_suite(suite, build(configured(Setup(first[0], rows=first[1], tilt=SWEEP_TILT))))
        bar.set_postfix_str("heat map")
        heat = study.heatmap()
        bar.update()
        bar.set_postfix_str("relief tie-back")
        relief = tieback.measure(suite.relief_techniques, suite.relief_magnitudes, suite.relief_rays,
                                 suite.relief_texels, backend, progress=bar.update)
    TABLE.write(out / "results.csv", study.rows)
    ALONG_TABLE.write(out / "along_span.csv", study.along)
    TIEBACK_TABLE.write(out / "tieback.csv", relief)
    THREADS_TABLE.write(out / threads_report.THREADS_FILE, threads)
    meta = {
        "header": clock.header(TITLE, command, study.gpu.summary, suite.name),
        "suite": suite, "software": study.gpu.software, "threads": threads, "cpu": cpu_model(),
        "python": platform.python_version(), "numpy": np.__version__, "numba": numba_module().__version__,
        "platform": platform.platform(),
    }
    plotted = write_plots(out, study.rows, study.along, relief, heat)
    write_bytes(out / "report.md", report_text(study.rows, relief, meta, plotted).encode("utf-8"))
    return study.rows
