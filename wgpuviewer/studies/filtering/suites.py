"""The filtering study's configurations (filter x derivative source x parameters), cases and suites, the columns
of its results.csv, and the command's options narrowing the suite."""

from __future__ import annotations

from dataclasses import dataclass, field

from wgpuviewer.core.errors import UserError
from wgpuviewer.harness import suite as harness_suite
from wgpuviewer.harness.table import Column, Table
from wgpuviewer.relief.filters import DERIVATIVE_SOURCES, FILTERS, get_filter
from wgpuviewer.relief.renderer import DrawConfig

from .views import TECHNIQUE, Case


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
class Suite(harness_suite.Suite):
    size: tuple[int, int]
    reference: int  # sub-pixel rays per pixel side (the convergence check uses half)
    cases: tuple[Case, ...]
    configs: tuple[Config, ...]
    frames: int
    warmup: int = 2


def _cases(reliefs, albedos, angles, footprints) -> tuple[Case, ...]:
    return tuple(Case(r, a, float(angle), float(fp)) for r in reliefs for a in albedos for angle in angles
                 for fp in footprints)


SUITES = harness_suite.suites(
    Suite("smoke", (48, 36), 16,
          (Case("bricks", "own", 80.0, 2.0), Case("bricks", "checker", 80.0, 2.0), Case("flat0", "photo", 60.0, 2.0)),
          SMOKE_CONFIGS, frames=3, warmup=1),
    Suite("full", (160, 120), 16,
          _cases(("bricks", "step", "wall"), ("own", "checker", "stripes", "photo"), (0.0, 45.0, 70.0, 80.0, 85.0),
                 (1.0, 4.0))
          + _cases(("flat0",), ("checker", "stripes", "photo"), (0.0, 45.0, 70.0, 80.0, 85.0), (1.0, 4.0)),
          _full_configs(), frames=10),
)

#: results.csv: one row per case x configuration.
TABLE = Table("filtering results", (
    Column("case", str), Column("relief", str), Column("albedo", str), Column("angle", float, "degrees"),
    Column("footprint", float, "texels per pixel"), Column("occluding", bool), Column("filter", str),
    Column("derivatives", str), Column("params", str), Column("label", str),
    Column("time_ratio", float, "x trilinear (uv)"), Column("gpu_ms", float, "ms, median"), Column("timer", str),
    Column("psnr", float, "dB"), Column("ssim", float), Column("psnr_gauss", float, "dB"),
    Column("psnr_occluded", float, "dB"), Column("occluded_share", float, "of the covered pixels"),
    Column("texels_per_pixel", float, "texels"), Column("depth_fetches_per_pixel", float, "fetches"),
    Column("hidden_per_pixel", float, "texels"), Column("capped_share", float, "of the covered pixels"),
    Column("bounded_share", float, "of the covered pixels"), Column("ratio_p50", float, "x"),
    Column("ratio_p99", float, "x"), Column("ratio_max", float, "x"), Column("reference_psnr_half", float, "dB"),
    Column("pixels", int, "covered pixels"), Column("adapter", str),
))


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

    base = harness_suite.pick(SUITES, suite)
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
