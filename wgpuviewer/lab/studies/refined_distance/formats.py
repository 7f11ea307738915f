"""Memory and build time of every auxiliary map format a search technique binds (distance, distance_refined, cone,
maxmip, quadmax), as the renderer builds and uploads it (``relief.maps``: the volume plan's slices and sub-cells,
the uploaded texture format), at several sizes, on the GPU path and on the CPU reference. A build that would take
longer than ``budget_s`` is not run: its time is extrapolated from the largest size measured, in proportion to
the texels (every kernel here does bounded work per texel), and marked as such.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

import maptools
from maptools.kinds.cone.slot import CONE_FILTER, CONE_MAX_RATIO, footprint_min_depth
from maptools.kinds.distance_refined.slot import REFINED_BANDS, REFINED_MAX_ANGLE, REFINED_SECTORS
from maptools.kinds.maxmip.slot import cell_max_height, maxmip_atlas, quadmax_atlas
from maptools.volume.slot import uploaded_volume
from wgpuviewer.lab.bench.view import HEIGHT_SCALE
from wgpuviewer.relief.maps import volume_plan

FORMATS = ("distance", "distance_refined", "cone", "maxmip", "quadmax")
BACKENDS = ("gpu", "cpu")


@dataclass
class Built:
    format: str
    size: int  # texels per side
    backend: str
    build_s: float  # uncached
    extrapolated: bool  # seconds estimated from a smaller size (not run)
    bytes_per_texel: float  # the uploaded texture(s), per height-map texel
    settings: str  # what the renderer builds it with here (slices, sub-cells, bins)


def build(fmt: str, height: np.ndarray, backend: str, gpu) -> tuple[float, str]:
    """Bytes per texel of ``fmt`` as uploaded and the settings, after one uncached build on ``backend``."""
    h, w = height.shape
    depth = 1.0 - height.astype(np.float64)
    if fmt in ("distance", "distance_refined"):
        plan = volume_plan(gpu, fmt, w, h)
        extra = ({"max_angle": REFINED_MAX_ANGLE, "sectors": REFINED_SECTORS, "bands": REFINED_BANDS}
                 if fmt == "distance_refined" else {})
        volume = uploaded_volume(maptools.generate(fmt, height, backend=backend, slices=plan.slices,
                                                   subcells=plan.subcells, height_scale=HEIGHT_SCALE, **extra))
        bins = f", {REFINED_SECTORS}x{REFINED_BANDS} bins + plain" if extra else ""
        return volume.nbytes / (w * h), f"{plan.slices} slices, {plan.subcells}² sub-cells{bins}, {volume.dtype}"
    if fmt == "cone":
        ratios = maptools.generate("cone", height, backend=backend, max_ratio=CONE_MAX_RATIO, filter=CONE_FILTER)
        packed = np.stack([np.asarray(ratios, np.float32), footprint_min_depth(depth, gpu.depth_format)], axis=-1)
        return packed.nbytes / (w * h), "rg32float (ratio, footprint min depth)"
    levels = maptools.generate("maxmip", cell_max_height(depth), backend=backend)
    if fmt == "maxmip":
        return maxmip_atlas(levels).nbytes / (w * h), "r32float atlas of the levels"
    return quadmax_atlas(depth, levels).nbytes / (w * h), "rgba32uint atlas (14-bit leaves, node maxima)"


def measure(heights: dict[int, np.ndarray], gpu, budget_s: float, formats=FORMATS, on_built=None) -> list[Built]:
    """Every format x backend x size of ``heights`` (size -> square height map, ascending): measured while the
    estimate (the previous size's time x the texel ratio) stays within ``budget_s``, else extrapolated;
    ``on_built`` is called with each result as it comes."""
    out: list[Built] = []
    for fmt in formats:
        for backend in BACKENDS:
            last: tuple[int, float] | None = None
            for size, height in sorted(heights.items()):
                estimate = last[1] * (size / last[0]) ** 2 if last else 0.0
                if last and estimate > budget_s:
                    bpt, settings = _settings_only(fmt, size, gpu, out)
                    out.append(Built(fmt, size, backend, estimate, True, bpt, settings))
                    if on_built:
                        on_built(out[-1])
                    continue
                t0 = time.perf_counter()
                bpt, settings = build(fmt, height, backend, gpu)
                seconds = time.perf_counter() - t0
                out.append(Built(fmt, size, backend, seconds, False, bpt, settings))
                last = (size, seconds)
                if on_built:
                    on_built(out[-1])
    return out


def _settings_only(fmt: str, size: int, gpu, done: list[Built]) -> tuple[float, str]:
    """Bytes per texel and settings of a build that is not run: a build of the same size, else for a volume its
    plan at that size (the largest build's item size and volume count), else the largest build's."""
    built = [b for b in done if b.format == fmt and not b.extrapolated]
    same = [b for b in built if b.size == size]
    if same:
        return same[0].bytes_per_texel, same[0].settings
    largest = max(built, key=lambda b: b.size)
    if fmt not in ("distance", "distance_refined"):
        return largest.bytes_per_texel, largest.settings
    plan, was = volume_plan(gpu, fmt, size, size), volume_plan(gpu, fmt, largest.size, largest.size)
    settings = largest.settings.replace(f"{was.slices} slices, {was.subcells}²", f"{plan.slices} slices, "
                                                                               f"{plan.subcells}²")
    return largest.bytes_per_texel * plan.slices / was.slices, settings
