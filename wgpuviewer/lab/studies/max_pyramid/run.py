"""``wgpuviewer max-pyramid``: the paper's max-pyramid walk (the ``maxmip`` technique; ``quadmax``, its packed
variant, beside it) against the linear searches (steep, POM, relief) on the benchmark's full-screen views
(``bench.view``, the frame's rays traced by the GPU probe), on reliefs with large flat areas and noisy ones, 0-89°:
each technique's SIMD-tile fetches (``simd_tile_cost``) and hit error (p95 and max, texels, against the float64 exact
hit), the linear searches swept over their layer counts (compare.py makes equal error and equal cost of the
sweeps); the instrumented twin of the walk (twin.py, checked against the probe ray by ray) gives the per-level step
statistics the paper asserts and the paper's early exit. Writes results.csv, levels.csv, sweep.csv, the pictures
and report.md after each height map.
"""

from __future__ import annotations

import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from wgpuviewer.core.io import write_bytes
from wgpuviewer.lab.harness import suite as harness_suite
from wgpuviewer.lab.harness.header import Clock

from . import reliefs
from .compare import cost_at_error, error_at_cost
from .report import report
from .tables import LEVELS, LEVELS_TABLE, SWEEP_TABLE, TABLE
from .twin import levels, walk

#: The walks under test (technique, parameters) and the linear searches swept (technique, its layer parameter).
TRACERS = ("maxmip", "quadmax")
LINEAR = (("steep", "layers"), ("pom", "layers"), ("relief", "linear_steps"))
#: The error targets of "equal error": p95 and max hit error, texels.
P95_TARGET = 0.25
MAX_TARGET = 1.0
HEIGHT_SCALE = 0.05  # the benchmark's relief depth (bench.view)


@dataclass(frozen=True)
class Suite(harness_suite.Suite):
    heightmaps: tuple[str, ...]
    angles: tuple[float, ...]
    resolution: tuple[int, int]  # frame (W, H): one ray per pixel, SIMD tiles of 8x4
    size: int  # texels per side of every map (at most 2**LEVELS / 2)
    layers: tuple[int, ...]  # the linear searches' sweep


SUITES = harness_suite.suites(
    Suite("smoke", ("bricks", "bumps"), (85.0,), (16, 8), 32, (4, 16, 64)),
    Suite("full", reliefs.NAMES, (0.0, 30.0, 45.0, 60.0, 75.0, 80.0, 85.0, 89.0), (64, 32), 256,
          (2, 4, 8, 16, 32, 64, 128, 256, 512, 1024)),
)
TITLE = "The max pyramid (Romanyuk & Dudnyk 2018) against the linear searches: SIMD-tile fetches at equal error"


def _scored(hits, ref, size, covered_shape) -> dict:
    """Fetches (mean, SIMD-tile) and hit error (p95, max) of probe ``hits`` against the exact ``ref``."""
    from wgpuviewer.relief.accuracy import simd_tile_cost
    from wgpuviewer.relief.reference import uv_error_texels

    err = uv_error_texels(hits.uv[ref.valid], ref.uv[ref.valid], size)
    fetches = hits.fetches.astype(np.float64).reshape(covered_shape)
    return {"fetches_mean": float(fetches.mean()), "fetches_simd": simd_tile_cost(fetches),
            "error_p95": float(np.percentile(err, 95)), "error_max": float(err.max()),
            "capped": float(np.mean(hits.capped))}


def _early_exit(heightmap, uv, v, t_from: float, w, ref, shape) -> dict:
    """The paper's early exit: the texel nearest the ray's entry into the relief (at t_from) holds the global
    maximum. How often it fires, the hit error it makes there, and the walk's SIMD-tile fetches with it (a fired ray:
    the top texel and the start texel; any other: its walk plus the start texel)."""
    from wgpuviewer.relief.accuracy import simd_tile_cost
    from wgpuviewer.relief.reference import uv_error_texels

    from .twin import MIN_VIEW_Z, as_probed

    h = heightmap.height
    wh = np.array([h.shape[1], h.shape[0]])
    frac, v32, offset = as_probed(uv, v)
    span = v32[:, :2] / np.maximum(v32[:, 2:3], MIN_VIEW_Z) * HEIGHT_SCALE
    entry = frac - span * t_from
    texel = np.mod(np.round(entry * wh - 0.5).astype(np.int64), wh)
    fired = h[texel[:, 1], texel[:, 0]] >= h.max()
    err = uv_error_texels(entry[fired & ref.valid] + offset[fired & ref.valid], ref.uv[fired & ref.valid],
                          heightmap.size)
    with_exit = np.where(fired, 2, w.fetches + 1).astype(np.float64).reshape(shape)
    return {"early_exit_share": float(fired.mean()), "early_exit_error_max": float(err.max()) if err.size else None,
            "early_exit_simd": simd_tile_cost(with_exit)}


def _competitors(row: dict, sweeps: dict) -> None:
    """Each linear search's SIMD-tile cost at the error targets and its errors at the row's SIMD-tile cost."""
    for name, _ in LINEAR:
        p95 = [(s["fetches_simd"], s["error_p95"]) for s in sweeps[name]]
        mx = [(s["fetches_simd"], s["error_max"]) for s in sweeps[name]]
        row[f"{name}_simd_p95"], row[f"{name}_flag_p95"] = cost_at_error(p95, P95_TARGET)
        row[f"{name}_simd_max"], row[f"{name}_flag_max"] = cost_at_error(mx, MAX_TARGET)
        row[f"{name}_p95_at_simd"], row[f"{name}_flag_p95_at_simd"] = error_at_cost(p95, row["fetches_simd"])
        row[f"{name}_max_at_simd"], row[f"{name}_flag_max_at_simd"] = error_at_cost(mx, row["fetches_simd"])


def measure_view(heightmap, angle: float, suite: Suite, t_from: float) -> tuple[list, list, list]:
    """(results rows, levels rows, sweep rows) of one height map at one angle."""
    from wgpuviewer.lab.bench.view import make_view
    from wgpuviewer.relief.probe import probe
    from wgpuviewer.relief.reference import exact_hit

    view = make_view(heightmap, angle, suite.resolution)
    shape = view.uv0.shape[:2]
    uv, v = view.uv0.reshape(-1, 2), view.v_ts.reshape(-1, 3)
    depth = 1.0 - heightmap.height.astype(np.float64)
    ref = exact_hit(depth, uv, v, HEIGHT_SCALE)
    base = {"heightmap": heightmap.name, "relief_class": reliefs.CLASSES[heightmap.name], "angle": angle}
    sweep, sweeps = [], {}
    for name, param in LINEAR:
        sweeps[name] = []
        for n in suite.layers:
            scored = {**base, "technique": name, "layers": n,
                      **_scored(probe(name, heightmap.height, uv, v, HEIGHT_SCALE, **{param: n}), ref,
                                heightmap.size, shape)}
            sweeps[name].append(scored)
            sweep.append(scored)
    w = walk(depth, uv, v, HEIGHT_SCALE, t_from)
    stats = levels(w)
    rows = []
    for tracer in TRACERS:
        hits = probe(tracer, heightmap.height, uv, v, HEIGHT_SCALE)
        scored = _scored(hits, ref, heightmap.size, shape)
        sweep.append({**base, "technique": tracer, "layers": None, **scored})
        row = {**TABLE.blank(), **base, "tracer": tracer, "rays": len(uv), **scored}
        _competitors(row, sweeps)
        if tracer == "maxmip":
            from wgpuviewer.relief.reference import uv_error_texels

            row["twin_same_fetches"] = float(np.mean(w.fetches == hits.fetches))
            apart = uv_error_texels(w.uv, hits.uv, heightmap.size)
            row["twin_hit_diff"], row["twin_hits_agree"] = float(apart.max()), float(np.mean(apart <= 1e-3))
            row["twin_error_max"] = float(uv_error_texels(w.uv[ref.valid], ref.uv[ref.valid], heightmap.size).max())
            row.update({f"steps_l{s.level}": s.steps_per_ray for s in stats if s.level < LEVELS})
            row["within_two"] = _within_two(stats)
            row["climbs"] = sum(s.climbs_per_ray for s in stats)
            row.update(_early_exit(heightmap, uv, v, t_from, w, ref, shape))
        rows.append(row)
    level_rows = [{**base, **vars(s)} for s in stats]
    return rows, level_rows, sweep


def _within_two(stats) -> float:
    """Share of all parent visits (every level below the top) with at most 2 steps inside the parent."""
    visits = sum(s.parent_visits for s in stats if s.parent_visits)
    return sum(s.within_two * s.parent_visits for s in stats if s.parent_visits) / visits if visits else float("nan")


def run(suite_name: str, out: Path, backend: str | None = None, progress: bool = True,
        command: str = "wgpuviewer max-pyramid", pictures: bool = True) -> tuple[list, list, list]:
    """Measure ``SUITES[suite_name]`` into ``out`` (results.csv, levels.csv, sweep.csv, report.md; the pictures once
    at the end unless ``pictures`` is False: on a software adapter they take longer than the smoke suite)."""
    from tqdm import tqdm

    from wgpuviewer.core.gpu import get_gpu
    from wgpuviewer.relief.maps import depth_range

    suite = harness_suite.pick(SUITES, suite_name)
    clock = Clock()
    gpu = get_gpu(backend, quiet=True)
    maps = reliefs.available(suite.heightmaps)
    rows, level_rows, sweep = [], [], []
    out = Path(out)  # checked and made by the command first (harness.study.run_study)
    with tempfile.TemporaryDirectory(prefix="wgpuviewer-maxpyr-") as workdir, \
            tqdm(total=len(maps) * len(suite.angles), desc="max-pyramid", unit="view", disable=not progress) as bar:
        for name in maps:
            heightmap = reliefs.load(name, suite.size, Path(workdir))
            t_from = depth_range(1.0 - heightmap.height, gpu.depth_format)[0]
            for angle in suite.angles:
                r, lv, sw = measure_view(heightmap, angle, suite, t_from)
                rows += r
                level_rows += lv
                sweep += sw
                bar.update()
            TABLE.write(out / "results.csv", rows)
            LEVELS_TABLE.write(out / "levels.csv", level_rows)
            SWEEP_TABLE.write(out / "sweep.csv", sweep)
            text = report(rows, level_rows, clock.header(TITLE, command, gpu.summary, suite.name), out, False)
            write_bytes(out / "report.md", text.encode())
    if pictures:
        text = report(rows, level_rows, clock.header(TITLE, command, gpu.summary, suite.name), out, True)
        write_bytes(out / "report.md", text.encode())
    return rows, level_rows, sweep
