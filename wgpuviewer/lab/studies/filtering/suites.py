"""The filtering study's configurations (filter x derivative source x parameters), cases and suites, the columns
of its results.csv, and the command's options narrowing the suite."""

from __future__ import annotations

from dataclasses import dataclass, field, replace

from wgpuviewer.core.errors import UserError
from wgpuviewer.lab.harness import suite as harness_suite
from wgpuviewer.lab.harness.table import Column, Table
from wgpuviewer.relief.filters import DERIVATIVE_SOURCES, FILTERS, get_filter
from wgpuviewer.relief.renderer import DrawConfig

from .views import TECHNIQUE, Case

#: The ray searches a configuration's render may use: the exact one (the reference's, so the filters are compared
#: on the true hits) and an approximate one (what a real-time renderer traces), as technique and parameters.
TRACERS = {"maxmip": (TECHNIQUE, ()), "pom32": ("pom", (("layers", 32),))}
EXACT = "maxmip"


@dataclass(frozen=True)
class Config:
    filter: str
    derivatives: str = "uv"
    params: tuple[tuple[str, object], ...] = ()
    tracer: str = EXACT

    @property
    def label(self) -> str:
        extra = " ".join(str(v) if k == "max_anisotropy" else f"{k}={v:g}" for k, v in self.params)
        tracer = "" if self.tracer == EXACT else f" [{self.tracer}]"
        return f"{self.filter}{' ' + extra if extra else ''} ({self.derivatives}){tracer}"

    def on(self, tracer: str) -> Config:
        return replace(self, tracer=tracer)

    def draw(self) -> DrawConfig:
        technique, params = TRACERS[self.tracer]
        return DrawConfig.of(technique, dict(params), filter=self.filter, filter_params=dict(self.params),
                             derivatives=self.derivatives)


BASELINE = Config("trilinear", "uv")  # what a renderer does today; times are ratios to it on the same tracer
BILINEAR = Config("bilinear")  # level 0 at the hit: no footprint at all

#: Filters that sample through ``textureSampleGrad`` with the derivative source's gradients, and through which
#: kind of sampler: their footprint is the adapter's reading of those gradients, so where the adapter ignores
#: them (``relief.filter_probe``) their rows measure the driver, not the filter (tests/lab/studies/filtering pins
#: this list to the filters' WGSL).
EXPLICIT_GRADIENTS = {"trilinear": "isotropic", "aniso": "anisotropic"}


def _visibility_configs(tracer: str = EXACT) -> list[Config]:
    """The visibility filters on the two traced footprints (the paper's is the displaced one), dropping hidden
    texels; the full method also with the substitute inheriting their weight, the row-ends one on displaced."""
    out = []
    for name in ("ewa_vis", "ewa_vis_rows"):
        for source in ("displaced", "analytic"):
            out.append(Config(name, source, tracer=tracer))
    out += [Config("ewa_vis", s, (("inherit", 1),), tracer) for s in ("displaced", "analytic")]
    out.append(Config("ewa_vis_rows", "displaced", (("inherit", 1),), tracer))
    return out


def _full_configs() -> tuple[Config, ...]:
    """Every plain filter with every derivative source (nearest and bilinear take none), aniso at 4 and 16, EWA
    with Heckbert's alpha = 2 besides the default, the visibility filters (``_visibility_configs``); and after the
    approximate tracer (POM, 32 layers) the baselines, EWA and the paper's method with both weightings."""
    out = [BASELINE, Config("nearest"), BILINEAR]
    for name, f in FILTERS.items():
        if not f.uses_derivatives or f.visibility:
            continue
        for source in DERIVATIVE_SOURCES:
            if name == "aniso":
                out += [Config(name, source, (("max_anisotropy", a),)) for a in (4, 16)]
            elif (name, source) != ("trilinear", "uv"):
                out.append(Config(name, source))
    out.append(Config("ewa", "analytic", (("alpha", 2.0),)))
    out += _visibility_configs()
    approximate = [BASELINE, BILINEAR, Config("ewa", "displaced"), Config("ewa", "analytic"),
                   Config("ewa_vis", "displaced"), Config("ewa_vis", "displaced", (("inherit", 1),))]
    out += [c.on("pom32") for c in approximate]
    return tuple(out)


def _smoke_configs() -> tuple[Config, ...]:
    """The hardware filters on the unperturbed uv (what a renderer does today), bilinear, EWA with each source,
    the visibility filters with the two traced sources (inherit on displaced), two of them after POM."""
    out = [BASELINE, BILINEAR, Config("aniso", "uv", (("max_anisotropy", 16),)), Config("ewa", "uv"),
           Config("ewa", "displaced"), Config("ewa", "analytic"), Config("ewa_vis", "displaced"),
           Config("ewa_vis", "analytic"), Config("ewa_vis_rows", "displaced"),
           Config("ewa_vis", "displaced", (("inherit", 1),))]
    return tuple(out + [BASELINE.on("pom32"), Config("ewa_vis", "displaced", tracer="pom32")])


#: The tuning cases' configurations: EWA's one free accuracy parameter swept (alpha, the Gaussian's sharpness),
#: on cases kept apart from those that rank the filters, with the two baselines.
TUNING_ALPHAS = (2.0, 3.0, 4.0, 6.0, 8.0)
TUNING_CONFIGS = (BASELINE, BILINEAR, *(Config("ewa", "analytic", (("alpha", a),)) for a in TUNING_ALPHAS))


@dataclass(frozen=True)
class Flicker:
    """The temporal-stability sweep: ``frames`` frames of ``size`` pixels, the camera moving ``step`` texels per
    frame along the frame's x axis (sub-texel: every phase of the texel grid is seen), on the suite's cases at
    ``angles``; the reference of each frame at ``rays`` x ``rays`` rays per pixel."""

    frames: int = 16
    size: tuple[int, int] = (80, 60)
    step: float = 0.37
    rays: int = 8
    angles: tuple[float, ...] = (80.0,)
    footprints: tuple[float, ...] = (2.0,)


@dataclass(frozen=True)
class Suite(harness_suite.Suite):
    size: tuple[int, int]
    reference: int  # sub-pixel rays per pixel side (the convergence check uses half)
    cases: tuple[Case, ...]
    configs: tuple[Config, ...]
    frames: int
    warmup: int = 1
    #: Most rays per pixel side the reference is raised to where its own error hides a compared difference.
    max_reference: int = 32
    tuning: tuple[Case, ...] = ()  # the cases EWA's alpha is tuned on (never ranked)
    tuning_configs: tuple[Config, ...] = TUNING_CONFIGS
    flicker: Flicker | None = Flicker()


def _cases(reliefs, albedos, angles, footprints) -> tuple[Case, ...]:
    return tuple(Case(r, a, float(angle), float(fp)) for r in reliefs for a in albedos for angle in angles
                 for fp in footprints)


ALL_ALBEDOS = ("own", "checker", "stripes", "photo", "masked")
#: The order the full suite measures its cases in, so that a run stopped early (``./dev gpu-suite``'s time box)
#: has the grazing view at the middle footprint on every relief and albedo first.
ANGLE_ORDER = (80.0, 45.0, 85.0, 70.0, 0.0)
FOOTPRINT_ORDER = (2.0, 1.0, 4.0)


def by_priority(cases: tuple[Case, ...]) -> tuple[Case, ...]:
    def key(case: Case):
        def rank(order, value):
            return order.index(value) if value in order else len(order)

        return rank(ANGLE_ORDER, case.angle), rank(FOOTPRINT_ORDER, case.footprint)

    return tuple(sorted(cases, key=key))  # stable: relief and albedo keep their order within a rank
TUNING_CASES = _cases(("bumps",), ("own", "checker", "masked"), (60.0, 75.0), (2.0,))

SUITES = harness_suite.suites(
    Suite("smoke", (48, 36), 16,
          (Case("bricks", "own", 80.0, 2.0), Case("bricks", "masked", 80.0, 2.0), Case("flat0", "photo", 60.0, 2.0)),
          _smoke_configs(), frames=2, warmup=0, max_reference=16, tuning=(Case("bumps", "masked", 75.0, 2.0),),
          flicker=Flicker(frames=4, size=(24, 18), angles=(80.0,), footprints=(2.0,))),
    Suite("full", (160, 120), 16,
          by_priority(_cases(("bricks", "step", "wall"), ALL_ALBEDOS, (0.0, 45.0, 70.0, 80.0, 85.0), (1.0, 2.0, 4.0))
                      + _cases(("flat0",), ("checker", "stripes", "photo", "masked"), (0.0, 45.0, 70.0, 80.0, 85.0),
                               (1.0, 2.0, 4.0))),
          _full_configs(), frames=10, tuning=TUNING_CASES),
)

RUN_FILE = "run.json"  # beside results.csv: what report.md's header needs when it is made again from the results

#: results.csv: one row per case x configuration.
TABLE = Table("filtering results", (
    Column("case", str), Column("role", str, "rank: ranks the filters; tune: tunes EWA's alpha"),
    Column("relief", str), Column("albedo", str), Column("angle", float, "degrees"),
    Column("footprint", float, "texels per pixel"), Column("occluding", bool), Column("filter", str),
    Column("derivatives", str), Column("params", str), Column("tracer", str), Column("label", str),
    Column("void", str, "why the row is not a valid measurement of the filter ('' when valid)"),
    Column("time_ratio", float, "x trilinear (uv), same tracer"), Column("gpu_ms", float, "ms, median"),
    Column("timer", str),
    Column("psnr", float, "dB"), Column("ssim", float), Column("psnr_gauss", float, "dB"),
    Column("psnr_occluded", float, "dB"), Column("occluded_share", float, "of the covered pixels"),
    Column("psnr_uncertainty", float, "dB: the reference's own error's bound on this PSNR"),
    Column("texels_per_pixel", float, "texels"), Column("depth_fetches_per_pixel", float, "fetches"),
    Column("hidden_per_pixel", float, "texels"), Column("capped_share", float, "of the covered pixels"),
    Column("bounded_share", float, "of the covered pixels"), Column("ratio_p50", float, "x"),
    Column("ratio_p99", float, "x"), Column("ratio_max", float, "x"),
    Column("reference_rays", int, "rays per pixel side"), Column("reference_psnr_half", float, "dB"),
    Column("reference_resolved", bool, "every compared difference of the case exceeds the reference's error"),
    Column("flicker_psnr", float, "dB: frame-to-frame change against the reference's"),
    Column("flicker_ratio", float, "RMS frame-to-frame change / the reference's"),
    Column("flicker_reference_psnr", float, "dB: the same for the reference at half the rays"),
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
    configs, tuning = base.configs, base.tuning
    if filters:
        for name in filters:
            get_filter(name, "--filters")
        configs = tuple(c for c in configs if c.filter in filters or c.on(EXACT) == BASELINE)
        tuning = tuning if "ewa" in filters else ()  # the tuning cases tune EWA
    return Options(replace(base, size=size or base.size, cases=cases, configs=configs, tuning=tuning,
                           frames=frames if frames is not None else base.frames),
                   backend, command or f"wgpuviewer filtering --suite {suite}")
