"""The scene benchmark's measurement: suites, the loop over scenes and views, results.csv.

Per scene (``scenes``) and view, every configuration (``configs``) is drawn with ``basic`` and the exact tracer in
one renderer: GPU time side by side (``relief.draw_timing``, round robin; ``ratio_to_basic`` = time / ``basic``'s
in the same run), then one offscreen render each (colour and trace data) compared with the exact tracer's render of
the same view at the same pixels (``measure``).
"""

from __future__ import annotations

import tempfile
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from wgpuviewer.core.gpu import get_gpu
from wgpuviewer.core.io import write_bytes
from wgpuviewer.lab.harness import suite as harness_suite
from wgpuviewer.lab.harness.header import Clock
from wgpuviewer.lab.harness.table import Column, Table

from . import scenes
from .configs import BASELINE, CONFIGS, EXACT, SMOKE_CONFIGS, config_key, configs
from .measure import compare, fetch_counts, inverse_footprint


@dataclass(frozen=True)
class Suite(harness_suite.Suite):
    scenes: tuple[str, ...]
    views: tuple[str, ...]
    size: tuple[int, int]
    frames: int  # timed frames per configuration and view
    configs: tuple[tuple[str, dict], ...]


SUITES = harness_suite.suites(
    Suite("smoke", ("default",), ("near",), (64, 36), 2, SMOKE_CONFIGS),
    Suite("full", scenes.SCENES, scenes.VIEWS, (384, 216), 3, CONFIGS),
)

RESULTS = Table("scene benchmark results", [
    Column("scene", str), Column("view", str, "near, far or grazing (scenes.VIEWS)"),
    Column("size", str, "pixels, WxH"), Column("technique", str), Column("params", str),
    Column("ratio_to_basic", float, "x: GPU time / basic's, side by side in one run"),
    Column("gpu_ms", float, "median ms per frame (software adapter: only ratios)"),
    Column("fetches_mean", float, "depth fetches per covered pixel"),
    Column("fetches_simd", float, "per 8x4 tile, the slowest lane's depth fetches"),
    Column("capped", float, "fraction of covered pixels whose ray hit its cap"),
    Column("px_err_p50", float, "screen pixels: median hit error against the exact tracer's hit"),
    Column("px_err_p95", float, "screen pixels: p95 hit error"),
    Column("px_err_over_half", float, "fraction of compared pixels with a hit error above 0.5 pixel"),
    Column("flip_mean", float, "NVIDIA FLIP against the exact render, mean over pixels either covers"),
    Column("psnr_db", float, "dB, sRGB colour against the exact render, pixels either covers"),
    Column("pixels", int, "pixels compared for the hit error"),
    Column("silhouette", float, "fraction of the pixels either covers that only one covers"),
    Column("timer", str, "timestamp or wall-net (core.pass_timing)"),
])


@dataclass
class Crop:
    """What the report's crops need of one view: the exact render, and per shown configuration its render and
    FLIP map."""

    scene: str
    view: str
    exact: np.ndarray  # (H, W, 3) uint8
    shown: dict  # (technique, params) -> ((H, W, 3) uint8, (H, W) FLIP)


def measure_view(renderer, draws, keys, size, frames, shown_keys) -> tuple[list[dict], np.ndarray, dict]:
    """Rows of one view (renderer: the scene seen from it), the exact render's colour and the shown configurations'
    colour and FLIP map."""
    from wgpuviewer.relief.draw_timing import time_draws

    timing = time_draws(renderer, draws, size, frames, 1)
    images = [renderer.render(d, size) for d in draws]
    basic, exact = images[0], images[1]
    inverse, ok = inverse_footprint(basic.data[:, :, :2], basic.covered)
    exact_capped = fetch_counts(exact.data)[1]
    base_ms = timing.results[0].median_ms
    rows, pictures = [], {}
    for key, t, image in zip(keys, timing.results, images):
        measured, flip = compare(image, exact, inverse, ok, exact_capped)
        rows.append({"technique": key[0], "params": key[1], "gpu_ms": t.median_ms, "timer": timing.timer,
                     "ratio_to_basic": t.median_ms / base_ms if base_ms > 0 else float("nan"), **measured})
        if key in shown_keys:
            pictures[key] = (image.color[:, :, :3], flip)
    return rows, exact.color[:, :, :3], {key: pictures[key] for key in shown_keys}


def run(out: Path, suite_name: str = "full", scene_names=None, size=None, backend=None, progress: bool = True,
        command: str = "wgpuviewer scene-bench") -> list[dict]:
    from tqdm import tqdm

    from wgpuviewer.relief.renderer import DrawConfig, Renderer

    from .report import shown_configs, write_report

    suite = harness_suite.pick(SUITES, suite_name)
    names = tuple(scene_names or suite.scenes)
    size = tuple(size or suite.size)
    chosen = [BASELINE, EXACT, *configs(suite.configs)]
    keys = [config_key(*c) for c in chosen]
    shown_keys = shown_configs(keys)
    draws = [DrawConfig.of(name, values) for name, values in chosen]
    gpu = get_gpu(backend, quiet=True)
    clock = Clock()
    rows, crops = [], []
    with tempfile.TemporaryDirectory(prefix="scene-bench-") as work, \
            tqdm(total=len(names) * len(suite.views), desc="scene-bench", disable=not progress or None,
                 leave=False) as bar:
        for name in names:
            scene = scenes.load(name, Path(work))
            base = Renderer(scene, gpu)
            for view, camera in scenes.views(scene.camera).items():
                if view not in suite.views:
                    continue
                renderer = Renderer(replace(scene, camera=camera), gpu, like=base)
                got, exact, shown = measure_view(renderer, draws, keys, size, suite.frames, shown_keys)
                rows += [{"scene": Path(name).stem, "view": view, "size": f"{size[0]}x{size[1]}", **r} for r in got]
                crops.append(Crop(Path(name).stem, view, exact, shown))
                bar.update(1)
    RESULTS.write(out / "results.csv", rows)
    header = clock.header("Scene benchmark: whole scenes in screen pixels and FLIP against the exact tracer", command,
                          gpu.summary, suite.name)
    write_bytes(out / "report.md", write_report(out, header, rows, crops, suite, size).encode("utf-8"))
    return rows
