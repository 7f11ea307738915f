"""The contact study's measurement: suites, rows, results.csv and report.md.

Per height map and view angle: ``rays`` random rays (``accuracy.random_rays``, seed 0) for the error against the float64
exact hit (``reference.exact_hit``; capped rays count as misses, as auto's table counts them) and auto's SIMD tiles
of rays (``autotable.tile_rays``: 16 tiles of 8 x 4 neighbouring rays) for the cost. Each pair runs one linear search
of ``linear_steps`` and gives both finishes the same ``extra`` fetches beyond it: relief ``binary_steps = extra``,
contact ``refine_steps = extra + 1`` (its last sub-step is the search's own sample), so both have the fetch bound
linear_steps + 1 + extra. Contact stops its second search at the first sub-step below the surface, so it often
fetches fewer: the mean and SIMD-tile fetches say how many each really paid.
"""

from __future__ import annotations

import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from wgpuviewer.core.gpu import get_gpu
from wgpuviewer.core.io import write_bytes
from wgpuviewer.lab.bench.view import load_heightmap
from wgpuviewer.lab.harness import suite as harness_suite
from wgpuviewer.lab.harness.header import Clock, Header
from wgpuviewer.lab.harness.table import Column, Table
from wgpuviewer.relief.accuracy import random_rays
from wgpuviewer.relief.probe import probe
from wgpuviewer.relief.reference import exact_hit, uv_error_texels
from wgpuviewer.techniques.auto.autotable import tile_rays

TITLE = "contact against relief at equal fetches"
HEIGHT_SCALE = 0.05  # relief depth in uv units (the accuracy suite's)
TECHNIQUES = ("relief", "contact")


@dataclass(frozen=True)
class Suite(harness_suite.Suite):
    heightmaps: tuple[str, ...]
    angles: tuple[float, ...]
    linear_steps: tuple[int, ...]
    extra: tuple[int, ...]  # fetches beyond the linear search
    rays: int
    builtin_size: int
    real_size: int = 0


SUITES = harness_suite.suites(
    Suite("smoke", ("bumps", "step"), (45.0, 80.0), (8,), (2,), rays=256, builtin_size=64),
    Suite("full", ("bricks", "bumps", "ridges", "spike", "step", "checker", "brick"), (30.0, 60.0, 80.0, 89.0),
          (8, 16), (1, 2, 4), rays=1024, builtin_size=128, real_size=256),
)

RESULTS = Table("contact study results", [
    Column("heightmap", str), Column("angle", float, "degrees from the normal"), Column("technique", str),
    Column("linear_steps", int), Column("extra", int, "fetches beyond the linear search (binary or refine steps)"),
    Column("fetch_bound", int, "linear_steps + 1 + extra: the most fetches a ray may count"),
    Column("err_p50", float, "texels, against the float64 exact hit"), Column("err_p95", float, "texels"),
    Column("fetches_mean", float, "depth fetches per ray"),
    Column("fetches_simd", float, "per 8x4 tile, the slowest lane's fetches, mean over tiles"),
    Column("capped", float, "fraction of the error rays flagged capped"),
])


def settings(technique: str, linear_steps: int, extra: int) -> dict:
    """The parameters that give ``technique`` ``extra`` fetches beyond a linear search of ``linear_steps``."""
    if technique == "relief":
        return {"linear_steps": linear_steps, "binary_steps": extra}
    return {"linear_steps": linear_steps, "refine_steps": extra + 1}


def measure(name: str, height: np.ndarray, suite: Suite, backend=None) -> list[dict]:
    """The rows of one height map: every angle, pair and technique."""
    rows = []
    size = height.shape[::-1]
    for angle in suite.angles:
        uv, view = random_rays(suite.rays, angle)
        ref = exact_hit(1.0 - height, uv, view, HEIGHT_SCALE)
        tile_uv, tile_view = tile_rays(angle, height.shape, np.random.default_rng(int(angle * 10)))
        for n in suite.linear_steps:
            for extra in suite.extra:
                for technique in TECHNIQUES:
                    params = settings(technique, n, extra)
                    got = probe(technique, height, uv, view, HEIGHT_SCALE, backend=backend, **params)
                    cost = probe(technique, height, tile_uv, tile_view, HEIGHT_SCALE, backend=backend, **params)
                    miss = got.capped | ~ref.valid
                    err = np.where(miss, np.inf, uv_error_texels(got.uv, np.nan_to_num(ref.uv), size))
                    rows.append({
                        "heightmap": name, "angle": angle, "technique": technique, "linear_steps": n, "extra": extra,
                        "fetch_bound": n + 1 + extra, "err_p50": float(np.percentile(err, 50)),
                        "err_p95": float(np.percentile(err, 95)), "fetches_mean": float(got.fetches.mean()),
                        "fetches_simd": float(cost.fetches.reshape(-1, 32).max(axis=1).mean()),
                        "capped": float(got.capped.mean()),
                    })
    return rows


def run(out: Path, suite_name: str = "full", backend=None, progress: bool = True,
        command: str = "wgpuviewer contact") -> list[dict]:
    from tqdm import tqdm

    from .report import report

    suite = harness_suite.pick(SUITES, suite_name)
    gpu = get_gpu(backend, quiet=True)
    clock = Clock()
    rows = []
    with tempfile.TemporaryDirectory() as work:  # the photographs' PNGs: not results
        for name in tqdm(suite.heightmaps, desc="contact", disable=not progress or None, leave=False):
            rows += measure(name, load_heightmap(name, suite.builtin_size, Path(work), suite.real_size).height,
                            suite, backend)
    RESULTS.write(out / "results.csv", rows)
    header = Header(TITLE, command, gpu.summary, suite.name, clock.started, clock.seconds)
    write_bytes(out / "report.md", "\n".join([*header.lines(), "", *report(rows), ""]).encode("utf-8"))
    return rows
