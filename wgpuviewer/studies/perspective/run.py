"""``wgpuviewer perspective --out DIR``: every method's speed and texture-coordinate error against float64.

Sweeps (each configuration: ``instances`` geometries whose texel density differs by a fraction of a percent, so
that the float32 rounding pattern is sampled rather than one fixed pattern; errors pooled over them):

- ``span_length``: span (frame) lengths at tilt ``SWEEP_TILT``, offset 0;
- ``tilt``: far-end angles up to nearly edge-on and past the horizon, at the suite's ``sweep_span``;
- ``magnitude``: texel offsets (heavy tiling) at ``sweep_span`` and ``SWEEP_TILT``;
- ``speed``: whole frames (and few long spans) timed on the GPU (timestamp queries, round robin, ratio to
  ``direct`` in the same run) and on the CPU (the numpy forms), with their errors and operation counts;

plus the error along the span at ``ALONG_SPAN`` pixels, a picture of where the incremental drift lands on a long
grazing quad, and the relief tie-back (``tieback``). Each method's float32 kernel is compared with its numpy twin
in every configuration (``gpu_max_ulp``, ``gpu_flag_mismatch``).
"""

from __future__ import annotations

import platform
import sys
import time
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from wgpuviewer.core.io import write_bytes
from wgpuviewer.harness import suite as harness_suite
from wgpuviewer.harness.header import Clock
from wgpuviewer.harness.table import Column, Table

from . import tieback
from .geometry import Quad, Reference, Setup, build, reference
from .methods import METHODS, Result, evaluate, ops_per_texel

SWEEP_TILT = 80.0  # degrees at the far end of the span: a grazing wall, still well before edge-on
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
    sweep_span: int  # span length of the tilt and magnitude sweeps
    speed_frames: tuple[tuple[int, int], ...]  # (span length, spans)
    gpu_repeats: int
    cpu_repeats: int
    heatmap_frame: tuple[int, int]
    relief_techniques: tuple[str, ...]
    relief_magnitudes: tuple[float, ...]
    relief_rays: int
    relief_texels: int


SUITES = harness_suite.suites(
    Suite("smoke", (256, 1920, 3840, 8192), (45.0, 80.0, 89.9, 95.0), (0.0, 1e4, 1e6), rows=4, instances=2,
                   sweep_span=1920, speed_frames=((1920, 128), (8192, 16)), gpu_repeats=7, cpu_repeats=2,
                   heatmap_frame=(480, 270), relief_techniques=("pom", "maxmip"),
                   relief_magnitudes=(0.0, 1e3, 1e5, 1e7), relief_rays=256, relief_texels=64),
    # Powers of two and their neighbours, and lengths between: the drift depends on the increment's low bits.
    Suite("full", (64, 128, 256, 512, 1000, 1024, 1366, 1920, 2048, 2560, 3000, 3840, 4095, 4096, 5000,
                           6000, 7680, 8192, 10000, 12000, 16383, 16384),
                  (30.0, 45.0, 60.0, 70.0, 75.0, 80.0, 85.0, 87.0, 89.0, 89.5, 89.9, 90.0, 95.0),
                  (0.0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7), rows=16, instances=8, sweep_span=3840,
                  speed_frames=((3840, 2160), (8192, 64)), gpu_repeats=15, cpu_repeats=3, heatmap_frame=(1920, 1080),
                  relief_techniques=("pom", "relief", "maxmip", "cone", "distance"),
                  relief_magnitudes=(0.0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7), relief_rays=4096, relief_texels=128),
)

#: results.csv: one row per sweep configuration x method x precision. A cell that does not apply to the row (the
#: GPU time outside the speed sweep, the kernel check of a method's second precision) is empty.
TABLE = Table("perspective results", (
    Column("suite", str), Column("sweep", str), Column("method", str), Column("family", str),
    Column("precision", str), Column("span_length", int, "pixels"), Column("spans", int),
    Column("tilt_deg", float, "degrees at the span's far end"), Column("offset_texels", float, "texels"),
    Column("coord_max_texels", float, "texels"), Column("max_err", float, "texels"), Column("p99_err", float, "texels"),
    Column("mean_err", float, "texels"), Column("max_err_px", float, "pixels"),
    Column("flagged_fraction", float, "of the pixels"), Column("undetected", int, "pixels"),
    Column("gpu_max_ulp", int, "float32 ulp"), Column("gpu_flag_mismatch", int, "pixels"),
    Column("gpu_ms", float, "ms, median"), Column("gpu_ratio", float, "x direct"),
    Column("gpu_spread", float, "interquartile range / median"), Column("cpu_ms", float, "ms, median"),
    Column("cpu_ratio", float, "x direct"), *(Column(f"{kind}_per_texel", float, "operations")
                                                for kind in ("adds", "muls", "divs", "guards", "int_adds")),
    Column("ops_per_span", float, "operations"), Column("paper_adds", int), Column("paper_muls", int),
    Column("paper_divs", int), Column("timer", str), Column("adapter", str),
))
COLUMNS = TABLE.names
#: along_span.csv: the error in bins along one long span.
ALONG_TABLE = Table("perspective along-span errors", (
    Column("method", str), Column("precision", str), Column("span_length", int, "pixels"),
    Column("n_start", int, "pixels"), Column("n_end", int, "pixels"), Column("max_err", float, "texels"),
    Column("mean_err", float, "texels"),
))
#: tieback.csv: relief techniques' hit uv at large texture coordinates (tieback.py).
TIEBACK_TABLE = Table("perspective relief tie-back", (
    Column("technique", str), Column("magnitude_uv", float, "UV units"), Column("variant", str),
    Column("texels", int), Column("rays", int), Column("angle_deg", float, "degrees"),
    Column("input_spacing_texels", float, "texels"), Column("max_err", float, "texels"),
    Column("p99_err", float, "texels"), Column("mean_err", float, "texels"),
    Column("capped_fraction", float, "of the rays"),
))


def instances(setup: Setup, count: int) -> list[Setup]:
    """``count`` geometries like ``setup``, texel density apart by 0.37 % steps (a different rounding pattern each)."""
    return [replace(setup, texels_per_unit=setup.texels_per_unit * (1.0 + 0.0037 * i)) for i in range(count)]


def variants() -> list[tuple[str, str]]:
    """(method, precision) of every evaluation, registry order."""
    return [(m.name, p) for m in METHODS.values() for p in m.precisions]


def ulp_difference(a: np.ndarray, b: np.ndarray) -> int:
    """Largest distance in float32 units in the last place between two float32 arrays of the same shape."""
    ia, ib = (np.asarray(x, np.float32).view(np.int32).astype(np.int64) for x in (a, b))
    ia, ib = (np.where(i < 0, np.int64(-(2**31)) - i, i) for i in (ia, ib))  # monotonic integer order
    return int(np.abs(ia - ib).max()) if ia.size else 0


@dataclass
class Pooled:
    """Errors of one method over a configuration's geometries."""

    errors: list[np.ndarray] = field(default_factory=list)  # texels, valid and unflagged pixels
    in_pixels: list[np.ndarray] = field(default_factory=list)  # the same errors over each pixel's footprint
    flagged: int = 0
    undetected: int = 0  # the reference says undefined, the method did not flag it
    pixels: int = 0
    per_pixel: list[np.ndarray] = field(default_factory=list)  # (R, L) with NaN where not compared (along-span)

    def add(self, ref: Reference, result: Result, keep_per_pixel: bool = False) -> None:
        ok = ref.valid & ~result.flagged
        err = np.hypot(result.u.astype(np.float64) - ref.u, result.v.astype(np.float64) - ref.v)
        self.errors.append(err[ok])
        self.in_pixels.append(err[ok] / ref.footprint[ok])
        self.flagged += int(result.flagged.sum())
        self.undetected += int((~ref.valid & ~result.flagged).sum())
        self.pixels += result.flagged.size
        if keep_per_pixel:
            self.per_pixel.append(np.where(ok, err, np.nan))

    def values(self) -> dict:
        e = np.concatenate(self.errors) if self.errors else np.empty(0)
        px = np.concatenate(self.in_pixels) if self.in_pixels else np.empty(0)
        nan = float("nan")
        return {
            "max_err": float(e.max()) if e.size else nan, "p99_err": float(np.percentile(e, 99)) if e.size else nan,
            "mean_err": float(e.mean()) if e.size else nan, "max_err_px": float(px.max()) if px.size else nan,
            "flagged_fraction": self.flagged / max(self.pixels, 1), "undetected": self.undetected,
        }


class Measurements:
    """One run's measurements: the device and kernels, the rows so far, the per-method operation counts."""

    def __init__(self, suite: Suite, backend: str | None):
        from wgpuviewer.core.gpu import get_gpu

        from .kernels import kernels_for

        self.suite = suite
        self.gpu = get_gpu(backend, quiet=True)
        self.kernels = kernels_for(self.gpu)
        self.rows: list[dict] = []
        self.along: list[dict] = []
        self.ops = {(name, p): ops_per_texel(name, p) for name, p in variants()}

    def base(self, sweep: str, method: str, precision: str, setup: Setup, spans: int) -> dict:
        m = METHODS.get(method)
        row = TABLE.blank()
        row.update({
            "suite": self.suite.name, "sweep": sweep, "method": method,
            "family": m.family if m else HARDWARE, "precision": precision, "span_length": setup.span_length,
            "spans": spans, "tilt_deg": setup.tilt, "offset_texels": setup.offset, "adapter": self.gpu.summary,
        })
        if m:
            ops = self.ops[(method, precision)]
            row.update({f"{kind}s_per_texel": ops.get(kind, (0.0, 0.0))[0] for kind in ("add", "mul", "div", "guard")})
            row["int_adds_per_texel"] = ops.get("int_add", (0.0, 0.0))[0]
            row["ops_per_span"] = sum(per_span for _, per_span in ops.values())
            if m.paper_ops:
                row["paper_adds"], row["paper_muls"], row["paper_divs"] = m.paper_ops
        return row

    def configuration(self, sweep: str, setup: Setup, count: int, along: bool = False) -> list[dict]:
        """Error rows of every method (and the rasteriser) on ``count`` geometries like ``setup``."""
        quads: list[Quad] = [build(s) for s in instances(setup, count)]
        refs = [reference(q.coefficients, q.spans) for q in quads]
        coord = max(float(max(np.abs(r.u[r.valid]).max(initial=0), np.abs(r.v[r.valid]).max(initial=0))) for r in refs)
        spans = sum(q.spans.count for q in quads)
        rows = []
        for name, precision in variants():
            pooled = Pooled()
            row = self.base(sweep, name, precision, setup, spans)
            for i, (quad, ref) in enumerate(zip(quads, refs)):
                result, _ = evaluate(name, precision, quad.coefficients, quad.spans)
                pooled.add(ref, result, keep_per_pixel=along)
                if i == 0 and precision == METHODS[name].precisions[0]:  # the kernel's twin
                    gpu = self.kernels.run(name, quad.coefficients, quad.spans)
                    row["gpu_flag_mismatch"] = int((gpu.flagged != result.flagged).sum())
                    row["gpu_max_ulp"] = max(ulp_difference(gpu.u, result.u), ulp_difference(gpu.v, result.v))
            row.update(pooled.values(), coord_max_texels=coord)
            rows.append(row)
            if along:
                self.add_along(name, precision, setup.span_length, pooled)
        if not quads[0].horizon:  # the rasteriser draws finite quads only
            from .hardware import hardware_uv

            pooled = Pooled()
            for quad, ref in zip(quads, refs):
                pooled.add(ref, hardware_uv(quad, self.gpu), keep_per_pixel=along)
            rows.append({**self.base(sweep, HARDWARE, "float32", setup, spans), **pooled.values(),
                         "coord_max_texels": coord})
            if along:
                self.add_along(HARDWARE, "float32", setup.span_length, pooled)
        return rows

    def add_along(self, method: str, precision: str, length: int, pooled: Pooled) -> None:
        err = np.concatenate(pooled.per_pixel, axis=0)
        edges = np.linspace(0, length, ALONG_BINS + 1).astype(int)
        for lo, hi in zip(edges[:-1], edges[1:]):
            part = err[:, lo:hi]
            seen = np.isfinite(part)
            self.along.append({
                "method": method, "precision": precision, "span_length": length, "n_start": int(lo), "n_end": int(hi),
                "max_err": float(np.nanmax(part)) if seen.any() else float("nan"),
                "mean_err": float(np.nanmean(part)) if seen.any() else float("nan"),
            })

    def speed(self, frame: tuple[int, int]) -> list[dict]:
        """GPU and CPU time of every method's float32 form on one frame, with its errors there.

        All kernels and the rasteriser's pass take turns in one run (core.timing): timestamp queries on hardware
        adapters, wall clock net of an empty pass on software ones (whose compute timestamps are unreliable)."""
        from wgpuviewer.core.timing import time_passes

        from .hardware import frame_recorder, hardware_uv, renderer_for

        setup = Setup(span_length=frame[0], rows=frame[1], tilt=SWEEP_TILT)
        quad = build(setup)
        ref = reference(quad.coefficients, quad.spans)
        names = list(METHODS)
        outputs = self.kernels.outputs(quad.spans)
        recorders = [self.kernels.prepare(n, quad.coefficients, quad.spans, outputs).record for n in names]
        renderer = renderer_for(quad, self.gpu)
        recorders.append(frame_recorder(quad, renderer))
        timings = time_passes(self.gpu.device, recorders, self.suite.gpu_repeats, warmup=2,
                              timestamps="timestamp-query" in self.gpu.features and not self.gpu.software)
        gpu_ms = dict(zip([*names, HARDWARE], timings.median_ms))
        # interquartile range of the single passes over their median: how far one pass's time is to be trusted
        spread = {n: float(np.subtract(*np.percentile(t, [75, 25])) / max(np.median(t), 1e-12))
                  for n, t in zip([*names, HARDWARE], timings.samples_ms)}
        rows = []
        cpu_ms = {}
        for name in names:
            precision = METHODS[name].precisions[0]
            times = []
            for _ in range(self.suite.cpu_repeats):
                start = time.perf_counter()
                result, _ = evaluate(name, precision, quad.coefficients, quad.spans)
                times.append((time.perf_counter() - start) * 1e3)
            cpu_ms[name] = float(np.median(times))
            pooled = Pooled()
            pooled.add(ref, result)
            rows.append({**self.base("speed", name, precision, setup, quad.spans.count), **pooled.values(),
                         "cpu_ms": cpu_ms[name], "cpu_ratio": cpu_ms[name] / cpu_ms[DIRECT]})
        pooled = Pooled()
        pooled.add(ref, hardware_uv(quad, self.gpu, renderer))
        rows.append({**self.base("speed", HARDWARE, "float32", setup, quad.spans.count), **pooled.values()})
        for row in rows:
            ms = gpu_ms[row["method"]]
            row.update(gpu_ms=ms, gpu_ratio=ms / gpu_ms[DIRECT] if gpu_ms[DIRECT] > 0 else float("nan"),
                       gpu_spread=spread[row["method"]], timer=timings.timer)
        return rows

    def heatmap(self) -> dict:
        """Per-pixel errors of the float32 incremental and direct forms on a long grazing quad, and its uv."""
        w, h = self.suite.heatmap_frame
        quad = build(Setup(span_length=w, rows=h, tilt=HEATMAP_TILT))
        ref = reference(quad.coefficients, quad.spans)
        out = {"setup": quad.setup, "reference": ref}
        for name in ("incremental", DIRECT):
            result, _ = evaluate(name, "float32", quad.coefficients, quad.spans)
            err = np.hypot(result.u - ref.u, result.v - ref.v)
            out[name] = np.where(ref.valid & ~result.flagged, err, np.nan)
        return out


def run(suite_name: str, out: Path, backend: str | None = None, progress: bool = True,
        command: str = "wgpuviewer perspective") -> list[dict]:
    """Run the study; write results.csv, along_span.csv, tieback.csv, report.md and the plots into ``out`` (the
    command checks and makes it first: ``harness.study.run_study``)."""
    from tqdm import tqdm

    from .plots import write_plots
    from .report import TITLE, report_text

    suite = harness_suite.pick(SUITES, suite_name)
    out = Path(out)
    clock = Clock()
    study = Measurements(suite, backend)
    configs = ([("span_length", Setup(span_length=n, rows=suite.rows, tilt=SWEEP_TILT)) for n in suite.span_lengths]
               + [("tilt", Setup(span_length=suite.sweep_span, rows=suite.rows, tilt=t)) for t in suite.tilts]
               + [("magnitude", Setup(span_length=suite.sweep_span, rows=suite.rows, tilt=SWEEP_TILT, offset=o))
                  for o in suite.offsets])
    relief_steps = len(suite.relief_techniques) * len(suite.relief_magnitudes) * len(tieback.VARIANTS)
    with tqdm(total=len(configs) + len(suite.speed_frames) + relief_steps + 1, desc="perspective", unit="step",
              file=sys.stderr, disable=not progress) as bar:
        for sweep, setup in configs:
            bar.set_postfix_str(f"{sweep} L={setup.span_length} tilt={setup.tilt:g} offset={setup.offset:g}")
            study.rows += study.configuration(sweep, setup, suite.instances,
                                              along=sweep == "span_length" and setup.span_length == ALONG_SPAN)
            bar.update()
        for frame in suite.speed_frames:
            bar.set_postfix_str(f"speed {frame[0]}x{frame[1]}")
            study.rows += study.speed(frame)
            bar.update()
        bar.set_postfix_str("heat map")
        heat = study.heatmap()
        bar.update()
        bar.set_postfix_str("relief tie-back")
        relief = tieback.measure(suite.relief_techniques, suite.relief_magnitudes, suite.relief_rays,
                                 suite.relief_texels, backend, progress=bar.update)
    TABLE.write(out / "results.csv", study.rows)
    ALONG_TABLE.write(out / "along_span.csv", study.along)
    TIEBACK_TABLE.write(out / "tieback.csv", relief)
    meta = {
        "header": clock.header(TITLE, command, study.gpu.summary, suite.name),
        "suite": suite, "software": study.gpu.software,
        "python": platform.python_version(), "numpy": np.__version__, "platform": platform.platform(),
    }
    plotted = write_plots(out, study.rows, study.along, relief, heat)
    write_bytes(out / "report.md", report_text(study.rows, relief, meta, plotted).encode("utf-8"))
    return study.rows
