"""``wgpuviewer bench``: speed against error of every registered technique, with a float64 reference.

For each height map x technique x parameter setting x view angle it measures, on a full-screen
view of the relief (bench/view.py):

- GPU time per frame (timestamp queries, median over ``frames`` frames after warm-up), with
  ``basic`` texturing timed side by side in the same run: ``ratio_to_basic`` = time / basic time;
- cost: depth fetches per pixel (mean, p95) from the techniques' own counters (the data target),
  and the fraction of rays that hit a cap;
- error against the float64 reference (reference.exact_hit): UV error in texels (mean, p95, max)
  over a regular subsample of pixels, and the PSNR of the image shaded on the CPU at the
  technique's hit UVs against the same shading at the reference hit UVs.

Techniques come from the registry (``techniques.TECHNIQUES``); ``SWEEPS`` lists the parameter
settings tried per technique name, and a technique it does not name runs with its registry
defaults, so new techniques are benchmarked without changes here.
"""

from __future__ import annotations

import platform
import sys
import tempfile
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from wgpuviewer.core.errors import UserError
from wgpuviewer.core.params import resolve_params
from wgpuviewer.lab.harness import suite as harness_suite
from wgpuviewer.lab.harness.header import Clock, Header
from wgpuviewer.lab.harness.table import Column, Table
from wgpuviewer.techniques import TECHNIQUES

#: Parameter settings per technique name (overrides of the registry defaults). Settings naming a
#: parameter the technique does not have are skipped; a technique not listed runs its defaults.
SWEEPS: dict[str, tuple[dict, ...]] = {
    "parallax": ({}, {"offset_limiting": True}),
    "steep": ({"layers": 8}, {"layers": 16}, {"layers": 32}, {"layers": 64}),
    "pom": tuple({"layers": n} for n in (4, 8, 16, 24, 32, 64, 128)),
    "pom_adaptive": ({},),
    "auto": ({"max_error": 0.25}, {"max_error": 0.5}, {"max_error": 1.0}),
}

#: The smoke suite's smaller sweeps (still all of Table 4.1's POM layer counts).
SMOKE_SWEEPS: dict[str, tuple[dict, ...]] = {
    "parallax": ({},),
    "steep": ({"layers": 16},),
    "pom": tuple({"layers": n} for n in (4, 8, 16, 24, 32, 64)),
    "pom_adaptive": ({},),
    "auto": ({"max_error": 0.25}, {"max_error": 0.5}),
}

BASELINE = "basic"
REAL_MAPS = ("brick", "grass", "gravel")  # scikit-image's bundled textures (optional)
SYNTHETIC_MAPS = ("bricks", "bumps", "ridges", "flat0", "flat1", "spike", "step", "wall", "checker")
ALL_ANGLES = (0.0, 30.0, 45.0, 60.0, 75.0, 80.0, 85.0, 89.0)


@dataclass(frozen=True)
class Suite(harness_suite.Suite):
    heightmaps: tuple[str, ...]
    angles: tuple[float, ...]
    resolution: tuple[int, int]
    frames: int
    warmup: int
    sweeps: dict = field(default_factory=dict)
    eval_pixels: int = 65536  # pixels per measurement compared with the reference
    builtin_size: int = 256
    real_size: int = 0  # scikit-image maps area-downscaled to at most this many texels per side (0: as bundled)
    simd_tile: tuple[int, int] = (8, 4)  # (width, height) pixels of the SIMD group in fetches_simd
    reference_workers: int = 0  # processes for the float64 reference hits (0: in this process)


SUITES = harness_suite.suites(
    Suite("smoke", ("brick", "bricks", "spike"), (0.0, 45.0, 60.0, 80.0, 89.0), (96, 54), 30, 3,
          SMOKE_SWEEPS, eval_pixels=1500, builtin_size=128, real_size=256),
    # 20 frames after 2 warm-up rounds: the whole suite in one 8-minute run on an H100-class GPU (docs/benchmarks.md)
    Suite("full", REAL_MAPS + SYNTHETIC_MAPS, ALL_ANGLES, (1920, 1080), 20, 2, SWEEPS,
          eval_pixels=32768, builtin_size=256, reference_workers=-1),
)

#: results.csv: one row per height map x configuration x angle.
TABLE = Table("benchmark results", (
    Column("suite", str), Column("heightmap", str), Column("heightmap_size", str, "texels, WxH"),
    Column("technique", str), Column("params", str), Column("angle", float, "degrees at the frame centre"),
    Column("angle_min", float, "degrees"), Column("angle_max", float, "degrees"),
    Column("resolution", str, "pixels, WxH"), Column("adapter", str), Column("backend", str), Column("timer", str),
    Column("frames", int, "timed frames"), Column("gpu_ms", float, "ms, median"), Column("basic_ms", float, "ms"),
    Column("ratio_to_basic", float, "x"), Column("fetches_mean", float, "depth fetches per pixel"),
    Column("fetches_p95", float, "depth fetches per pixel"), Column("uv_err_mean", float, "texels"),
    Column("uv_err_p95", float, "texels"), Column("uv_err_max", float, "texels"), Column("psnr_db", float, "dB"),
    Column("capped_fraction", float, "of the covered pixels"), Column("covered_fraction", float, "of the frame"),
    Column("eval_pixels", int, "pixels"),
    # the divergence-aware cost (mean over screen tiles of the tile's largest fetch count), the tile it was computed
    # for, and the memory of the height-derived maps the technique samples; the first H100 runs lack them
    Column("fetches_simd", float, "depth fetches per SIMD tile", optional=True, default=float("nan")),
    Column("simd_tile", str, "pixels, WxH", optional=True, default=""),
    Column("map_bytes", int, "bytes", optional=True),
))
COLUMNS = TABLE.names


def params_label(params: dict) -> str:
    if not params:
        return "-"
    return " ".join(f"{k}={str(v).lower() if isinstance(v, bool) else v}" for k, v in params.items())


def settings_for(name: str, sweeps: dict) -> list[dict]:
    """Full parameter dicts (registry defaults + overrides) to benchmark for technique ``name``."""
    technique = TECHNIQUES[name]
    known = {p.name for p in technique.params}
    out: list[dict] = []
    for overrides in sweeps.get(name, ({},)):
        if not set(overrides) <= known:
            continue  # the registry entry changed; this setting no longer applies
        values = resolve_params(technique, overrides)
        if values not in out:
            out.append(values)
    return out or [technique.defaults()]


def configs_for(techniques: list[str], sweeps: dict) -> list[tuple[str, dict]]:
    configs = [(BASELINE, TECHNIQUES[BASELINE].defaults())]
    for name in techniques:
        for values in settings_for(name, sweeps):
            if (name, values) not in configs:
                configs.append((name, values))
    return configs


def skimage_available() -> bool:
    try:
        import skimage.data  # noqa: F401
    except ImportError:
        return False
    return True


@dataclass
class Options:
    suite: Suite
    techniques: list[str]
    backend: str | None
    command: str
    notes: list[str] = field(default_factory=list)


def check_heightmaps(names) -> None:
    """A UserError naming --heightmaps for a name that is no builtin or scikit-image map, or a scikit-image map
    without scikit-image (bench and the studies check their option with it before any folder or GPU)."""
    from wgpuviewer.textures import BUILTINS

    known = (*BUILTINS, *REAL_MAPS)
    for name in names:
        if name not in known:
            raise UserError(f"--heightmaps: unknown height map {name!r}; expected some of {', '.join(known)}")
        if name in REAL_MAPS and not skimage_available():
            raise UserError(f"--heightmaps: {name!r} needs scikit-image; install it with "
                            f"pip install 'wgpuviewer[bench]'")


def resolve_options(suite_name: str, resolution=None, heightmaps=None, techniques=None, angles=None,
                    frames=None, backend=None, command="wgpuviewer bench", simd_tile=None) -> Options:
    """Validated run options (UserError naming the option on bad input)."""
    suite = harness_suite.pick(SUITES, suite_name)
    notes = []
    if resolution is not None:
        suite = replace(suite, resolution=tuple(resolution))
    if simd_tile is not None:
        suite = replace(suite, simd_tile=tuple(simd_tile))
    if frames is not None:
        if frames < 1:
            raise UserError(f"--frames {frames}: expected at least 1 (30 or more for a stable median)")
        suite = replace(suite, frames=frames)
    if angles is not None:
        for a in angles:
            if not 0.0 <= a <= 89.0:
                raise UserError(f"--angles: {a:g} out of range; expected 0 to 89 degrees "
                                f"(the frame spans about 1.5 degrees, and must not look past the horizon)")
        suite = replace(suite, angles=tuple(float(a) for a in angles))
    if heightmaps is not None:
        check_heightmaps(heightmaps)
        suite = replace(suite, heightmaps=tuple(heightmaps))
    elif not skimage_available():
        kept = tuple(h for h in suite.heightmaps if h not in REAL_MAPS)
        if kept != suite.heightmaps:
            notes.append("scikit-image is not installed: its real textures (brick, grass, gravel) were "
                         "left out (pip install 'wgpuviewer[bench]')")
            suite = replace(suite, heightmaps=kept or ("bricks",))
    if techniques is not None:
        for name in techniques:
            if name not in TECHNIQUES:
                raise UserError(f"--techniques: unknown technique {name!r}; expected some of {', '.join(TECHNIQUES)}")
        chosen = [t for t in TECHNIQUES if t in techniques]
    else:
        chosen = list(TECHNIQUES)
    if frames is not None and frames < 30:
        notes.append(f"--frames {frames}: fewer than 30 timed frames per configuration; medians are noisy")
    return Options(suite, chosen, backend, command, notes)


@dataclass
class Row:
    values: dict
    errors: np.ndarray  # per-pixel UV errors (texels), kept for pooled statistics


#: Bytes per texel of the formats the height-derived maps use (map memory per technique).
FORMAT_BYTES = {"r8unorm": 1, "r16float": 2, "r32float": 4, "rg32float": 8, "rgba8unorm": 4, "rgba16float": 8, "rgba32float": 16,
                "rgba32uint": 16}


def texture_bytes(texture) -> int:
    """GPU memory of a texture's texels, all mip levels (3D textures halve their depth too)."""
    w, h, d = texture.size
    total = 0
    for level in range(texture.mip_level_count):
        depth = max(d >> level, 1) if texture.dimension == "3d" else d
        total += max(w >> level, 1) * max(h >> level, 1) * depth
    return total * FORMAT_BYTES[texture.format]


def map_bytes(renderer, material: str, technique: str) -> int:
    """Memory of the height-derived maps (depth and what is built from it) ``technique`` samples on ``material``."""
    from wgpuviewer.relief.maps import MAP_SLOTS

    return sum(texture_bytes(renderer.texture(material, slot)) for slot in TECHNIQUES[technique].textures
               if MAP_SLOTS[slot].derived)


def _fetch_stats(capture, tile) -> dict:
    """Fetch statistics of one capture over the covered pixels: mean, p95 (from integer counts), SIMD-tile cost."""
    from wgpuviewer.relief.accuracy import simd_tile_cost

    from .capture import percentile_of_counts

    raw = capture.data[:, :, 3]
    covered = capture.covered
    capped = raw < 0
    image = np.where(capped, -raw - 1.0, raw) if capped.any() else raw  # fetch counts: whole numbers
    counted = image if covered.all() else image[covered]
    counts = np.bincount(counted.astype(np.int32).ravel()) if counted.size else np.zeros(1, np.int64)
    n = int(counts.sum())
    mean = float(counts @ np.arange(len(counts)) / n) if n else float("nan")
    n_capped = int(np.count_nonzero(capped & covered))
    return {"fetches_mean": mean, "fetches_p95": percentile_of_counts(counts, 95),
            "fetches_simd": simd_tile_cost(image, tile, covered),
            "capped_fraction": n_capped / n if n else float("nan"),
            "covered_fraction": float(covered.mean())}


def _view_rows(suite, heightmap, view, configs, timing, captures, sizes, pending_reference, adapter_backend):
    """The CSV rows of one view from its timing and captures (errors against the view's reference)."""
    from .view import Shader, errors

    adapter, backend = adapter_backend
    ref = pending_reference.result()
    shader = Shader(view)
    size = view.size
    basic_ms = timing.results[0].median_ms
    rows = []
    for (name, params), t, cap in zip(configs, timing.results, captures):
        err = errors(view, ref, cap.data, cap.covered, shader)
        e = err.uv_texels
        rows.append(Row({
            "suite": suite.name, "heightmap": heightmap.name,
            "heightmap_size": f"{heightmap.size[0]}x{heightmap.size[1]}",
            "technique": name, "params": params_label(params), "angle": view.angle,
            "angle_min": round(view.angle_min, 3), "angle_max": round(view.angle_max, 3),
            "resolution": f"{size[0]}x{size[1]}", "adapter": adapter, "backend": backend,
            "timer": timing.timer, "frames": suite.frames,
            "gpu_ms": t.median_ms, "basic_ms": basic_ms,
            "ratio_to_basic": t.median_ms / basic_ms if basic_ms > 0 else float("nan"),
            "uv_err_mean": float(e.mean()) if e.size else float("nan"),
            "uv_err_p95": float(np.percentile(e, 95)) if e.size else float("nan"),
            "uv_err_max": float(e.max()) if e.size else float("nan"),
            "psnr_db": err.psnr, "eval_pixels": err.pixels,
            **_fetch_stats(cap, suite.simd_tile),
            "simd_tile": f"{suite.simd_tile[0]}x{suite.simd_tile[1]}", "map_bytes": sizes[name],
        }, e))
    return rows


def run(options: Options, out: Path, progress: bool = True) -> list[dict]:
    """Run the benchmark; write ``out``/results.csv, report.md and plots. Returns the CSV rows.

    Phases: (1) every height map's views, and every map each configuration samples built up front (from the disk
    cache when it holds them; auto's tables measured), so the timed part only draws; (2) the float64 reference
    hits of every view, in a process pool when the suite asks for one (full: on all but one CPU core), while
    (3) the GPU part runs view by view: timing (one submit per round of frames), then every configuration's trace
    data in batches (one submit and two read-backs per batch); a worker thread turns each view's data into rows
    (fetch statistics, errors against the reference) while the GPU works on the next view."""
    import time

    from tqdm import tqdm

    from wgpuviewer.core.gpu import get_gpu
    from wgpuviewer.relief.renderer import DrawConfig

    from .view import reference_pool

    suite = options.suite
    gpu = get_gpu(options.backend, quiet=True)
    adapter = gpu.summary
    backend = gpu.adapter.info.get("backend_type", "")
    configs = configs_for(options.techniques, suite.sweeps)
    draws = [DrawConfig.of(name, params) for name, params in configs]
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    rows: list[Row] = []
    busy = []
    counters = {"submits": 0, "readbacks": 0}
    phases = {}
    clock = Clock()
    total = len(suite.heightmaps) * len(suite.angles) * len(configs)
    with tempfile.TemporaryDirectory(prefix="wgpuviewer-bench-") as workdir, \
            tqdm(total=total, desc="bench", unit="row", file=sys.stderr, disable=not progress) as bar:
        # (1) height maps, views and every map the configurations sample
        phase_start = time.perf_counter()
        work = _prepare(suite, configs, gpu, Path(workdir), options.notes, bar)
        phases["maps"] = time.perf_counter() - phase_start
        # (2) reference hits, all views at once (a pool works on them while the GPU part runs)
        phase_start = time.perf_counter()
        pending = reference_pool([v for _, views, _, _ in work for v in views], suite.eval_pixels,
                                 suite.reference_workers)
        gpu_s = 0.0
        processing: list = []  # one future per view: its rows, built while the GPU works on the next views

        def collect(block: bool):
            while processing and (block or processing[0].done()):
                new_rows = processing.pop(0).result()
                rows.extend(new_rows)
                bar.update(len(new_rows))
                TABLE.write(out / "results.csv", [r.values for r in rows])  # partial results survive a kill

        with ThreadPoolExecutor(max_workers=1) as worker:
            for index, (heightmap, views, first, sizes) in enumerate(work):
                for view in views:
                    bar.set_postfix_str(f"{heightmap.name} {view.angle:g}°")
                    timing, data, seconds = _gpu_part(view, gpu, first, configs, draws, suite, counters, busy)
                    gpu_s += seconds
                    collect(block=len(processing) >= 2)  # at most two views' data waiting
                    processing.append(worker.submit(_view_rows, suite, heightmap, view, configs, timing,
                                                    data.captures, sizes, pending.pop(0), (adapter, backend)))
                work[index] = (heightmap, views, None, sizes)  # this height map is done: free its maps and pipelines
            collect(block=True)
        phases["gpu"] = gpu_s
        phases["references and errors, not overlapped with the GPU part"] = time.perf_counter() - phase_start - gpu_s
    meta = {
        "header": clock.header(TITLE.format(suite=suite.name), options.command, adapter, suite.name),
        "suite": suite, "adapter": adapter, "backend": backend, "software": gpu.software,
        "timer": rows[0].values["timer"] if rows else "", "notes": options.notes, "configs": configs,
        "techniques": options.techniques, "busy_max": max(busy) if busy else float("nan"),
        "python": platform.python_version(), "platform": platform.platform(),
        "phases": phases, "counters": {**counters, "views": sum(len(w[1]) for w in work)},
    }
    TABLE.write(out / "results.csv", [r.values for r in rows])
    write_outputs(out, rows, meta)
    return [r.values for r in rows]


def _gpu_part(view, gpu, first, configs: list, draws: list, suite: Suite, counters: dict, busy: list) -> tuple:
    """Phase (3) of ``run`` for one view: timing (one submit per round of frames), then every configuration's trace
    data in batches; (timing, data, the seconds they took), the submit and read-back counters and the busy
    fractions updated."""
    import time

    from wgpuviewer.relief.renderer import Renderer

    from .capture import capture
    from .config_timing import time_configs

    gpu_clock = time.perf_counter()
    renderer = Renderer(view.scene, gpu, like=first)
    timing = time_configs(renderer, configs, suite.resolution, suite.frames, suite.warmup)
    data = capture(renderer, draws, suite.resolution)
    seconds = time.perf_counter() - gpu_clock
    counters["submits"] += timing.submits + data.submits
    counters["readbacks"] += timing.readbacks + data.readbacks
    busy.append(timing.busy_fraction)
    return timing, data, seconds


def _prepare(suite: Suite, configs: list, gpu, workdir: Path, notes: list[str], bar) -> list[tuple]:
    """Phase (1) of ``run``: per height map (a map that cannot be loaded is left out with a note), its views and a
    renderer with every map the configurations sample built, whose maps and pipelines the views share; (heightmap,
    views, that renderer, map bytes per technique) each."""
    from wgpuviewer.relief.renderer import Renderer

    from .view import load_heightmap, make_view

    work = []
    for map_name in suite.heightmaps:
        try:
            heightmap = load_heightmap(map_name, suite.builtin_size, workdir, suite.real_size)
        except Exception as e:  # noqa: BLE001 - e.g. scikit-image's data not loadable offline
            notes.append(f"height map {map_name!r} left out: {type(e).__name__}: {e}")
            bar.update(len(suite.angles) * len(configs))
            continue
        views = []
        for angle in suite.angles:
            try:
                views.append(make_view(heightmap, angle, suite.resolution))
            except ValueError as e:
                raise UserError(f"--angles {angle:g}: {e}") from None
        bar.set_postfix_str(f"{map_name}: maps")
        first = Renderer(views[0].scene, gpu)  # the views of this map share its maps and pipelines
        sizes = {name: map_bytes(first, "relief", name) for name in dict.fromkeys(n for n, _ in configs)}
        work.append((heightmap, views, first, sizes))
    return work


def write_outputs(out: Path, rows: list[Row], meta: dict) -> None:
    """report.md and the plots of ``rows`` into ``out``."""
    from wgpuviewer.core.io import write_bytes

    from .plots import plots
    from .report import report

    values = [r.values for r in rows]
    written, note = plots(out, values) if values else ([], "No rows: no plots.")
    write_bytes(out / "report.md", report(values, meta, written, note).encode("utf-8"))


#: The report's title (harness.header).
TITLE = "wgpuviewer benchmark: speed against error ({suite} suite)"


def rereport(csv_paths: list[Path], out: Path, command: str = "wgpuviewer bench") -> list[dict]:
    """report.md and plots again from one or more results.csv files (e.g. parts of one run)."""

    values = []
    for path in csv_paths:
        try:
            values += TABLE.read(path)
        except UserError as e:
            raise UserError(f"--from-csv {e}") from None
    if not values:
        raise UserError("--from-csv: no rows in " + ", ".join(map(str, csv_paths)))
    first = values[0]
    w, h = (int(x) for x in first["resolution"].split("x"))
    base = SUITES.get(first["suite"], SUITES["full"])
    suite = replace(base, resolution=(w, h), frames=int(first["frames"]),
                    heightmaps=tuple(dict.fromkeys(v["heightmap"] for v in values)),
                    angles=tuple(sorted({v["angle"] for v in values})))
    configs = list(dict.fromkeys((v["technique"], v["params"]) for v in values))
    adapters = sorted({v["adapter"] for v in values})
    adapter = " / ".join(adapters)
    meta = {
        "header": Header(TITLE.format(suite=suite.name), command, adapter, suite.name, None, None,
                         tuple(Path(p).name for p in csv_paths)),
        "suite": suite, "adapter": adapter, "backend": first["backend"],
        "software": "(CPU)" in first["adapter"] or "llvmpipe" in first["adapter"], "timer": first["timer"],
        "notes": [] if len(adapters) == 1 else ["rows from several adapters: compare ratios per adapter only"],
        "configs": configs, "techniques": list(dict.fromkeys(v["technique"] for v in values)),
        "busy_max": float("nan"), "python": platform.python_version(), "platform": platform.platform(),
    }
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    TABLE.write(out / "results.csv", values)
    write_outputs(out, [Row(v, np.empty(0)) for v in values], meta)
    return values
