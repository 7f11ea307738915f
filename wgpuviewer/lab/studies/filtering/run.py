"""``wgpuviewer filtering``: every filter x derivative source x tracer on every case, against the supersampled
reference.

Per case (relief x albedo x view angle x minification, ``views``): the reference at ``reference`` x ``reference``
rays per pixel and at half that (its own error), then per configuration one render of the filtered albedo
(``mode="albedo"``: the albedo lookup alone, unlit) with its statistics, and the GPU time of all configurations
drawn round robin in the same renderer (``relief.draw_timing``), as a ratio to ``trilinear`` on the unperturbed uv
after the same tracer. Errors: PSNR and SSIM (scikit-image) of the sRGB image against the box-filtered reference
over the pixels the plane covers, PSNR against the Gaussian reference, and PSNR over the pixels whose footprint
contains hidden texels (``supersample.occluded_pixels``).

The reference's own error bounds every PSNR (``psnr_uncertainty``); where it hides a difference the study
compares (``COMPARED``), the reference is raised to twice the rays, up to the suite's ``max_reference``. Rows of a
filter the adapter cannot run as specified (explicit gradients ignored: ``void_reason``) are kept and marked void.
The tuning cases (``Suite.tuning``) sweep EWA's alpha apart from the ranked cases. The flicker sweep
(``Suite.flicker``) renders a short camera slide per configuration and compares each frame-to-frame change with
the reference's.
"""

from __future__ import annotations

import json
import math
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from wgpuviewer.core.errors import UserError
from wgpuviewer.core.gpu import get_gpu
from wgpuviewer.core.io import write_bytes
from wgpuviewer.lab.harness.header import Clock
from wgpuviewer.relief.filters import FLAGS
from wgpuviewer.relief.renderer import Renderer

from .suites import BASELINE, EXACT, EXPLICIT_GRADIENTS, RUN_FILE, Config, Options, Suite
from .supersample import Supersample, supersample
from .views import Case, View, make_view

PSNR_CAP = 99.0  # dB, for identical images
#: Differences the study compares per case (label pairs on the same tracer): visibility against plain EWA on the
#: same footprint, inheriting against dropping, EWA against the two baselines. The reference is raised where its
#: error hides one of them that is at least EQUAL_DB.
COMPARED = (
    ("ewa_vis (displaced)", "ewa (displaced)"), ("ewa_vis (analytic)", "ewa (analytic)"),
    ("ewa_vis inherit=1 (displaced)", "ewa_vis (displaced)"), ("ewa_vis inherit=1 (analytic)", "ewa_vis (analytic)"),
    ("ewa (analytic)", "trilinear (uv)"), ("ewa (analytic)", "bilinear (uv)"),
)
EQUAL_DB = 0.1  # differences below this are reported as equal, resolved or not


def psnr(a: np.ndarray, b: np.ndarray) -> float:
    if a.size == 0:
        return float("nan")
    mse = float(np.mean((a - b) ** 2))
    return PSNR_CAP if mse <= 10 ** (-PSNR_CAP / 10) else float(-10 * np.log10(mse))


def ssim(a: np.ndarray, b: np.ndarray) -> float:
    try:
        from skimage.metrics import structural_similarity
    except ImportError:
        raise UserError("the filtering study's SSIM needs scikit-image: pip install 'wgpuviewer[bench]'") from None

    return float(structural_similarity(a, b, channel_axis=2, data_range=1.0, win_size=7))


def psnr_uncertainty(value: float, reference_error: float) -> float:
    """dB by which a PSNR ``value`` against the reference may differ from the PSNR against the true image, when the
    reference is ``reference_error`` (RMS) from it: |RMS(A - R) - RMS(A - T)| <= RMS(R - T)."""
    rms = 10 ** (-value / 20)
    return float(20 * np.log10(1 + reference_error / max(rms, 1e-12)))


def void_reason(config: Config, gpu) -> str:
    """Why ``config``'s rows cannot measure its filter on ``gpu`` ('' when they can): a filter that samples through
    ``textureSampleGrad`` on an adapter that ignores the explicit gradients through that kind of sampler."""
    kind = EXPLICIT_GRADIENTS.get(config.filter)
    if kind is None:
        return ""
    from wgpuviewer.relief.filter_probe import explicit_gradient_note

    return explicit_gradient_note(gpu, kind)


@dataclass
class CaseResult:
    """One case's reference and renders (kept for the report's pictures)."""

    case: Case
    reference: Supersample
    images: dict  # Config -> (H, W, 3) float64 sRGB


def _errors(color: np.ndarray, ref: Supersample, reference_error: float) -> dict:
    mask, occluded = ref.covered, ref.occluded & ref.covered
    filled = np.where(mask[..., None], color, ref.color)  # SSIM over the frame: uncovered pixels agree
    value = psnr(color[mask], ref.color[mask])
    return {"psnr": value, "ssim": ssim(filled, ref.color), "psnr_gauss": psnr(color[mask], ref.gauss[mask]),
            "psnr_occluded": psnr(color[occluded], ref.color[occluded]) if occluded.any() else float("nan"),
            "occluded_share": float(occluded.sum() / max(mask.sum(), 1)),
            "psnr_uncertainty": psnr_uncertainty(value, reference_error), "reference_rays": ref.n,
            "pixels": int(mask.sum())}


def _reference_error(half: Supersample, full: Supersample) -> tuple[float, float]:
    """RMS and PSNR of the half-ray reference against the full one over the covered pixels."""
    mask = full.covered
    diff = half.color[mask] - full.color[mask]
    return (float(np.sqrt(np.mean(diff ** 2))) if diff.size else 0.0), psnr(half.color[mask], full.color[mask])


def unresolved(rows: list[dict]) -> list[tuple[str, str]]:
    """The compared pairs of one case (per tracer) whose PSNR difference is at least EQUAL_DB but within the
    two rows' reference uncertainties."""
    out = []
    by = {(r["tracer"], r["label"].replace(f" [{r['tracer']}]", "")): r for r in rows if not r.get("void")}
    for tracer in {r["tracer"] for r in rows}:
        for a, b in COMPARED:
            ra, rb = by.get((tracer, a)), by.get((tracer, b))
            if ra is None or rb is None:
                continue
            gap = abs(ra["psnr"] - rb["psnr"])
            if EQUAL_DB <= gap <= ra["psnr_uncertainty"] + rb["psnr_uncertainty"]:
                out.append((ra["label"], rb["label"]))
    return out


def measure_case(view: View, suite: Suite, configs, gpu, void: dict, progress=None) -> tuple[list[dict], CaseResult]:
    from wgpuviewer.relief.draw_timing import time_draws

    renderer = Renderer(view.scene, gpu)
    n = suite.reference
    half = supersample(renderer, view, max(n // 2, 1))
    ref = supersample(renderer, view, n)
    error, reference_half = _reference_error(half, ref)
    mask = ref.covered
    rows, images = [], {}
    for config in configs:
        image = renderer.render(config.draw(), view.size, view.camera, mode="albedo")
        color = image.color[:, :, :3].astype(np.float64) / 255.0
        images[config] = color
        stats = image.filter[mask]
        flags = stats[:, 2] >> 24
        ratio = stats[:, 3].view(np.float32).astype(np.float64)
        rows.append({
            "filter": config.filter, "derivatives": config.derivatives, "tracer": config.tracer,
            "params": " ".join(f"{k}={v}" for k, v in config.params), "label": config.label,
            "void": void[config], **_errors(color, ref, error),
            "texels_per_pixel": float(stats[:, 0].mean()) if len(stats) else 0.0,
            "depth_fetches_per_pixel": float(stats[:, 1].mean()) if len(stats) else 0.0,
            "hidden_per_pixel": float((stats[:, 2] & 0xFFFFFF).mean()) if len(stats) else 0.0,
            "capped_share": float(((flags & FLAGS["capped"]) > 0).mean()) if len(stats) else 0.0,
            "bounded_share": float(((flags & FLAGS["bounded"]) > 0).mean()) if len(stats) else 0.0,
            "ratio_p50": float(np.percentile(ratio, 50)) if len(ratio) else 1.0,
            "ratio_p99": float(np.percentile(ratio, 99)) if len(ratio) else 1.0,
            "ratio_max": float(ratio.max()) if len(ratio) else 1.0,
        })
        if progress:
            progress()
    # Raise the rays where the reference's own error hides a compared difference (the old full is the new half).
    while unresolved(rows) and ref.n * 2 <= suite.max_reference:
        half, ref = ref, supersample(renderer, view, ref.n * 2)
        error, reference_half = _reference_error(half, ref)
        for row, config in zip(rows, configs):
            row.update(_errors(images[config], ref, error))
    resolved = not unresolved(rows)
    timing = time_draws(renderer, [c.draw() for c in configs], view.size, suite.frames, suite.warmup,
                        mode="albedo")
    base = {c.tracer: r.median_ms for c, r in zip(configs, timing.results) if c.on(EXACT) == BASELINE}
    for row, config, result in zip(rows, configs, timing.results):
        reference_ms = base.get(config.tracer, float("nan"))
        row.update(gpu_ms=result.median_ms, timer=timing.timer,
                   time_ratio=result.median_ms / reference_ms if reference_ms > 0 else float("nan"))
    case = view.case
    for row in rows:
        row.update(case=case.name, relief=case.relief, albedo=case.albedo, angle=case.angle, footprint=case.footprint,
                   occluding=case.occluding, adapter=gpu.summary, reference_psnr_half=reference_half,
                   reference_resolved=resolved, flicker_psnr=float("nan"), flicker_ratio=float("nan"),
                   flicker_reference_psnr=float("nan"))
    return rows, CaseResult(case, ref, images)


def flicker_psnr(frames: np.ndarray, reference: np.ndarray, mask: np.ndarray) -> float:
    """PSNR of the frame-to-frame changes (T-1, H, W, 3) of ``frames`` against those of ``reference`` over ``mask``:
    high when the picture changes as the true one does, low when it shimmers (or smears the true motion)."""
    return psnr(np.diff(frames, axis=0)[:, mask], np.diff(reference, axis=0)[:, mask])


def flicker_ratio(frames: np.ndarray, reference: np.ndarray, mask: np.ndarray) -> float:
    """RMS frame-to-frame change of ``frames`` over the reference's: above 1 shimmers, below 1 smooths."""
    def rms(x):
        return float(np.sqrt(np.mean(np.diff(x, axis=0)[:, mask] ** 2)))

    r = rms(reference)
    return rms(frames) / r if r > 0 else float("nan")


def measure_flicker(case: Case, suite: Suite, configs, gpu, folder: Path, progress=None) -> dict:
    """label -> (flicker_psnr, flicker_ratio, the reference's own flicker_psnr at half the rays) for ``case`` on
    the suite's flicker sweep."""
    sweep = suite.flicker
    view = make_view(case, sweep.size, folder)
    renderer = Renderer(view.scene, gpu)
    full, half, covered = [], [], []
    images = {c: [] for c in configs}
    for k in range(sweep.frames):
        moved = view.shifted(k * sweep.step)
        ref = supersample(renderer, moved, sweep.rays)
        full.append(ref.color)
        covered.append(ref.covered)
        half.append(supersample(renderer, moved, max(sweep.rays // 2, 1)).color)
        for config in configs:
            image = renderer.render(config.draw(), sweep.size, moved.camera, mode="albedo")
            images[config].append(image.color[:, :, :3].astype(np.float64) / 255.0)
        if progress:
            progress()
    mask = np.logical_and.reduce(covered)
    full, half = np.stack(full), np.stack(half)
    own = flicker_psnr(half, full, mask)
    return {c.label: (flicker_psnr(np.stack(images[c]), full, mask), flicker_ratio(np.stack(images[c]), full, mask),
                      own) for c in configs}


def run(options: Options, out: Path, progress: bool = True) -> list[dict]:
    """Measure the suite into ``out``: the tuning cases, then every case (with its flicker sweep where the suite
    asks for one). results.csv and run.json are written after every case, so a run stopped by Ctrl-C or SIGTERM
    (``./dev gpu-suite``'s time box) keeps the cases it finished and reports on them before it stops."""
    from tqdm import tqdm

    from . import report

    suite = options.suite
    out = Path(out)  # checked and made by the command first (harness.study.run_study)
    gpu = get_gpu(options.backend)
    textures = out / "textures"
    void = {c: void_reason(c, gpu) for c in (*suite.configs, *suite.tuning_configs)}
    notes = sorted({v for v in void.values() if v})
    sweep = suite.flicker
    flicker_cases = {c for c in suite.cases if sweep and c.angle in sweep.angles and c.footprint in sweep.footprints}
    valid = [c for c in suite.configs if not void[c]]
    total = (len(suite.cases) * len(suite.configs) + len(suite.tuning) * len(suite.tuning_configs)
             + len(flicker_cases) * (sweep.frames if sweep else 0))
    rows, kept = [], []
    clock = Clock()

    def save(stopped: str = "") -> dict:
        record = run_record(options, clock.header(report.TITLE, options.command, gpu.summary, suite.name), notes)
        record["stopped"] = stopped
        report.TABLE.write(out / "results.csv", rows)
        write_bytes(out / RUN_FILE, json.dumps(record, indent=1).encode())
        return record

    done = 0
    with tqdm(total=total, desc="filtering", file=sys.stderr, disable=not progress, leave=False) as bar:
        try:
            for case in suite.tuning:
                case_rows, _ = measure_case(make_view(case, suite.size, textures), suite, suite.tuning_configs, gpu,
                                            void, bar.update)
                rows += [{**row, "role": "tune"} for row in case_rows]
                save()
            for case in suite.cases:
                case_rows, result = measure_case(make_view(case, suite.size, textures), suite, suite.configs, gpu,
                                                 void, bar.update)
                if case in flicker_cases:
                    measured = measure_flicker(case, suite, valid, gpu, textures, lambda: bar.update(1))
                    for row in case_rows:
                        if row["label"] in measured:
                            row["flicker_psnr"], row["flicker_ratio"], row["flicker_reference_psnr"] = \
                                measured[row["label"]]
                rows += [{**row, "role": "rank"} for row in case_rows]
                if report.wanted_for_pictures(case, suite):
                    kept.append(result)
                done += 1
                save()
        except KeyboardInterrupt:
            if done:  # report the finished cases, then stop as asked
                record = save(f"stopped after {done} of {len(suite.cases)} cases")
                report.write(out, report.TABLE.read(out / "results.csv"), kept, record)
            raise
    record = save()
    rows = report.TABLE.read(out / "results.csv")  # the report quotes the numbers as results.csv holds them
    report.write(out, rows, kept, record)
    return rows


def run_record(options: Options, header, notes: list[str]) -> dict:
    """What the report needs besides results.csv: the header and the suite's settings (run.json)."""
    suite = options.suite
    sweep = suite.flicker
    return {
        "title": header.title, "command": header.command, "adapter": header.adapter, "suite": header.suite,
        "started": header.started.isoformat() if header.started else None,
        "seconds": None if header.seconds is None or not math.isfinite(header.seconds) else round(header.seconds, 1),
        "size": list(suite.size), "reference": suite.reference, "max_reference": suite.max_reference,
        "frames": suite.frames, "cases": len(suite.cases), "configs": len(suite.configs),
        "tuning_cases": len(suite.tuning),
        "flicker": None if sweep is None else {"frames": sweep.frames, "size": list(sweep.size), "step": sweep.step,
                                               "rays": sweep.rays, "angles": list(sweep.angles),
                                               "footprints": list(sweep.footprints)},
        "void_notes": notes,
    }
