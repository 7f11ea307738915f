"""``wgpuviewer filtering``: every filter x derivative source on every case, against the supersampled reference.

Per case (relief x albedo x view angle x minification, ``views``): the reference at ``reference`` x ``reference``
rays per pixel (and at half that, to state the reference's own error), then per configuration one render of the
filtered albedo (``mode="albedo"``: the albedo lookup alone, unlit) with its statistics, and the GPU time of all
configurations drawn round robin in the same renderer (``relief.timing``), as a ratio to ``trilinear`` on the
unperturbed uv. Errors: PSNR and SSIM (scikit-image) of the sRGB image against the box-filtered reference over the
pixels the plane covers, PSNR against the Gaussian reference, and PSNR over the pixels whose footprint contains
hidden texels (``supersample.occluded_pixels``).
"""

from __future__ import annotations

import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from wgpuviewer.core.gpu import get_gpu
from wgpuviewer.harness.header import Clock
from wgpuviewer.relief.filters import FLAGS
from wgpuviewer.relief.renderer import Renderer

from .suites import BASELINE, Options, Suite
from .supersample import supersample
from .views import Case, View, make_view

PSNR_CAP = 99.0  # dB, for identical images


def psnr(a: np.ndarray, b: np.ndarray) -> float:
    if a.size == 0:
        return float("nan")
    mse = float(np.mean((a - b) ** 2))
    return PSNR_CAP if mse <= 10 ** (-PSNR_CAP / 10) else float(-10 * np.log10(mse))


def ssim(a: np.ndarray, b: np.ndarray) -> float:
    from skimage.metrics import structural_similarity

    return float(structural_similarity(a, b, channel_axis=2, data_range=1.0, win_size=7))


@dataclass
class CaseResult:
    """One case's reference and renders (kept for the report's pictures)."""

    case: Case
    reference: object  # supersample.Supersample
    images: dict  # Config -> (H, W, 3) float64 sRGB


def measure_case(view: View, suite: Suite, gpu, progress=None) -> tuple[list[dict], CaseResult]:
    from wgpuviewer.relief.timing import time_draws

    renderer = Renderer(view.scene, gpu)
    ref = supersample(renderer, view, suite.reference)
    half = supersample(renderer, view, max(suite.reference // 2, 1))
    mask = ref.covered
    reference_half = psnr(half.color[mask], ref.color[mask])
    rows, images = [], {}
    for config in suite.configs:
        image = renderer.render(config.draw(), view.size, view.camera, mode="albedo")
        color = image.color[:, :, :3].astype(np.float64) / 255.0
        images[config] = color
        stats = image.filter[mask]
        flags = stats[:, 2] >> 24
        ratio = stats[:, 3].view(np.float32).astype(np.float64)
        filled = np.where(mask[..., None], color, ref.color)  # SSIM over the frame: uncovered pixels agree
        occluded = ref.occluded & mask
        rows.append({
            "filter": config.filter, "derivatives": config.derivatives,
            "params": " ".join(f"{k}={v}" for k, v in config.params), "label": config.label,
            "psnr": psnr(color[mask], ref.color[mask]), "ssim": ssim(filled, ref.color),
            "psnr_gauss": psnr(color[mask], ref.gauss[mask]),
            "psnr_occluded": psnr(color[occluded], ref.color[occluded]) if occluded.any() else float("nan"),
            "occluded_share": float(occluded.sum() / max(mask.sum(), 1)),
            "texels_per_pixel": float(stats[:, 0].mean()) if len(stats) else 0.0,
            "depth_fetches_per_pixel": float(stats[:, 1].mean()) if len(stats) else 0.0,
            "hidden_per_pixel": float((stats[:, 2] & 0xFFFFFF).mean()) if len(stats) else 0.0,
            "capped_share": float(((flags & FLAGS["capped"]) > 0).mean()) if len(stats) else 0.0,
            "bounded_share": float(((flags & FLAGS["bounded"]) > 0).mean()) if len(stats) else 0.0,
            "ratio_p50": float(np.percentile(ratio, 50)) if len(ratio) else 1.0,
            "ratio_p99": float(np.percentile(ratio, 99)) if len(ratio) else 1.0,
            "ratio_max": float(ratio.max()) if len(ratio) else 1.0,
            "reference_psnr_half": reference_half, "pixels": int(mask.sum()),
        })
        if progress:
            progress()
    timing = time_draws(renderer, [c.draw() for c in suite.configs], view.size, suite.frames, suite.warmup,
                        mode="albedo")
    base = timing.results[suite.configs.index(BASELINE)].median_ms
    for row, result in zip(rows, timing.results):
        row.update(gpu_ms=result.median_ms, time_ratio=result.median_ms / base if base > 0 else float("nan"),
                   timer=timing.timer)
    case = view.case
    for row in rows:
        row.update(case=case.name, relief=case.relief, albedo=case.albedo, angle=case.angle, footprint=case.footprint,
                   occluding=case.occluding, adapter=gpu.summary)
    return rows, CaseResult(case, ref, images)


def run(options: Options, out: Path, progress: bool = True) -> list[dict]:
    from . import report

    suite = options.suite
    out = Path(out)  # checked and made by the command first (harness.study.run_study)
    gpu = get_gpu(options.backend)
    rows, kept = [], []
    total = len(suite.cases) * len(suite.configs)
    from tqdm import tqdm

    clock = Clock()
    with tqdm(total=total, desc="filtering", file=sys.stderr, disable=not progress, leave=False) as bar:
        for case in suite.cases:
            view = make_view(case, suite.size, out / "textures")
            case_rows, result = measure_case(view, suite, gpu, bar.update)
            rows += case_rows
            if report.wanted_for_pictures(case, suite):
                kept.append(result)
    header = clock.header(report.TITLE, options.command, gpu.summary, suite.name)
    report.write(out, rows, kept, options, header)
    return rows

