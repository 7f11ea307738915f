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
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from wgpuviewer.core.errors import UserError
from wgpuviewer.core.gpu import get_gpu
from wgpuviewer.relief.filters import DERIVATIVE_SOURCES, FILTERS, FLAGS, get_filter
from wgpuviewer.relief.renderer import DrawConfig, Renderer

from .supersample import supersample
from .views import TECHNIQUE, Case, View, make_view

PSNR_CAP = 99.0  # dB, for identical images


@dataclass(frozen=True)
class Config:
    filter: str
    derivatives: str = "uv"
    params: tuple[tuple[str, object], ...] = ()

    @property
    def label(self) -> str:
        extra = " ".join(str(v) if k == "max_anisotropy" else f"{k}={v:g}" for k, v in self.params)
        return f"{self.filter}{' ' + extra if extra else ''} ({self.derivatives})"

    def draw(self) -> DrawConfig:
        return DrawConfig.of(TECHNIQUE, filter=self.filter, filter_params=dict(self.params),
                             derivatives=self.derivatives)


BASELINE = Config("trilinear", "uv")


def _full_configs() -> tuple[Config, ...]:
    """Every filter with every derivative source (nearest and bilinear take none), aniso at 4 and 16, and EWA
    with Heckbert's alpha = 2 besides the default."""
    out = [BASELINE, Config("nearest"), Config("bilinear")]
    for name, f in FILTERS.items():
        if not f.uses_derivatives:
            continue
        for source in DERIVATIVE_SOURCES:
            if name == "aniso":
                out += [Config(name, source, (("max_anisotropy", a),)) for a in (4, 16)]
            elif (name, source) != ("trilinear", "uv"):
                out.append(Config(name, source))
    out.append(Config("ewa", "analytic", (("alpha", 2.0),)))
    return tuple(out)


#: The smoke suite's: the hardware filters on the unperturbed uv (what a renderer does today), EWA with each
#: source, the visibility filters with the two displaced sources.
SMOKE_CONFIGS = (BASELINE, Config("aniso", "uv", (("max_anisotropy", 16),)), Config("ewa", "uv"),
                 Config("ewa", "displaced"), Config("ewa", "analytic"), Config("ewa_vis", "displaced"),
                 Config("ewa_vis", "analytic"), Config("ewa_vis_rows", "displaced"))


@dataclass(frozen=True)
class Suite:
    name: str
    size: tuple[int, int]
    reference: int  # sub-pixel rays per pixel side (the convergence check uses half)
    cases: tuple[Case, ...]
    configs: tuple[Config, ...]
    frames: int
    warmup: int = 2


def _cases(reliefs, albedos, angles, footprints) -> tuple[Case, ...]:
    return tuple(Case(r, a, float(angle), float(fp)) for r in reliefs for a in albedos for angle in angles
                 for fp in footprints)


SUITES = {
    "smoke": Suite("smoke", (48, 36), 16,
                   (Case("bricks", "own", 80.0, 2.0), Case("bricks", "checker", 80.0, 2.0),
                    Case("flat0", "photo", 60.0, 2.0)),
                   SMOKE_CONFIGS, frames=3, warmup=1),
    "full": Suite("full", (160, 120), 16,
                  _cases(("bricks", "step", "wall"), ("own", "checker", "stripes", "photo"), (0.0, 45.0, 70.0, 80.0, 85.0),
                         (1.0, 4.0))
                  + _cases(("flat0",), ("checker", "stripes", "photo"), (0.0, 45.0, 70.0, 80.0, 85.0), (1.0, 4.0)),
                  _full_configs(), frames=10),
}

COLUMNS = ("case", "relief", "albedo", "angle", "footprint", "occluding", "filter", "derivatives", "params", "label",
           "time_ratio", "gpu_ms", "timer", "psnr", "ssim", "psnr_gauss", "psnr_occluded", "occluded_share",
           "texels_per_pixel", "depth_fetches_per_pixel", "hidden_per_pixel", "capped_share", "bounded_share",
           "ratio_p50", "ratio_p99", "ratio_max", "reference_psnr_half", "pixels", "adapter")


@dataclass
class Options:
    suite: Suite
    backend: str | None = None
    command: str = "wgpuviewer filtering"
    notes: list[str] = field(default_factory=list)


def resolve_options(suite: str, *, size: tuple[int, int] | None = None, frames: int | None = None,
                    reliefs: list[str] | None = None, albedos: list[str] | None = None,
                    angles: list[float] | None = None, footprints: list[float] | None = None,
                    filters: list[str] | None = None, backend=None, command: str = "") -> Options:
    """The suite, narrowed or resized by the command's options (checked; a bad value is a UserError)."""
    from .views import ALBEDOS, HORIZON_MARGIN, RELIEFS

    base = SUITES[suite]
    for name in reliefs or ():
        if name not in RELIEFS:
            raise UserError(f"--reliefs: unknown relief {name!r}; expected some of {', '.join(RELIEFS)}")
    for name in albedos or ():
        if name not in ALBEDOS:
            raise UserError(f"--albedos: unknown albedo {name!r}; expected some of {', '.join(ALBEDOS)}")
    top = 90.0 - 2 * HORIZON_MARGIN
    for angle in angles or ():
        if not 0.0 <= angle <= top:
            raise UserError(f"--angles: {angle:g} degrees is out of range; expected 0 to {top:g}")
    for fp in footprints or ():
        if not 0.0 < fp <= 64.0:
            raise UserError(f"--footprints: {fp:g} texels per pixel is out of range; expected more than 0, up to 64")
    if frames is not None and frames < 1:
        raise UserError(f"--frames {frames}: expected at least 1 timed frame")
    cases = base.cases
    if reliefs or albedos or angles or footprints:
        def distinct(key):
            return list(dict.fromkeys(getattr(c, key) for c in base.cases))

        cases = _cases(reliefs or distinct("relief"), albedos or distinct("albedo"), angles or distinct("angle"),
                       footprints or distinct("footprint"))
    configs = base.configs
    if filters:
        for name in filters:
            get_filter(name, "--filters")
        configs = tuple(c for c in configs if c.filter in filters or c == BASELINE)
    return Options(Suite(base.name, size or base.size, base.reference, cases, configs,
                         frames if frames is not None else base.frames, base.warmup),
                   backend, command or f"wgpuviewer filtering --suite {suite}")


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
    out = Path(out)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as error:
        raise UserError(f"--out {out}: cannot create the folder ({error.strerror})") from None
    gpu = get_gpu(options.backend)
    rows, kept = [], []
    total = len(suite.cases) * len(suite.configs)
    from tqdm import tqdm

    started = time.perf_counter()
    with tqdm(total=total, desc="filtering", file=sys.stderr, disable=not progress, leave=False) as bar:
        for case in suite.cases:
            view = make_view(case, suite.size, out / "textures")
            case_rows, result = measure_case(view, suite, gpu, bar.update)
            rows += case_rows
            if report.wanted_for_pictures(case, suite):
                kept.append(result)
    report.write(out, rows, kept, options, time.perf_counter() - started)
    return rows

