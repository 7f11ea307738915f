"""``auto``'s cost/error table: the probe measures every candidate of ``AUTO_CANDIDATES`` on the material's
own depth map at the edges of auto's view-angle bins; per bin and error budget the cheapest candidate that meets the
budget at both edges of the bin is chosen, and the choices go to the GPU as a small texture (``table_texture``).

Measurement (``measure``): at every angle (0 and the bin edges, ``edge_angles``) ``ERROR_RAYS`` independent random rays
(entry points all over the map, random azimuths) for the error and ``TILES`` screen tiles of 8 x 4 rays for the cost
(``tile_rays``: a random entry point and azimuth per tile, rays ``TILE_SPACING`` texels apart, like neighbouring
pixels of a SIMD group); per candidate and angle the p95 and p97.5 UV error (texels) against the float64 exact hit
(capped rays count as misses), the mean fetches and the SIMD-tile cost (mean over tiles of the tile's largest fetch
count, ``accuracy.simd_tile_cost``'s definition) of the tiles. A candidate meets budget B in a bin when its p97.5 is within B at
both edges (twice the margin the p95 budget asks for: the table's rays are a sample, and a view sees only part of
the map); its cost there is the larger SIMD-tile cost of the two edges times ``COST_WEIGHTS`` (the time of one of
its fetches in POM fetches). Where no candidate meets the budget, the most accurate one is used and the table says
so (its error channel exceeds the budget).

POM's layer count and relief's linear steps scale with tan(angle) inside a bin (``scaled_layers``, auto.wgsl's
auto_layers): a candidate's count n holds at the bin's upper edge, and below it the count that keeps the layers'
horizontal spacing, down to ``lower_edge_layers(n)`` at the lower edge. So the table measures every such candidate
twice per angle: with n (for the bin that ends there) and with ``lower_edge_layers(n)`` (for the bin that starts
there; rows after the candidates, ``SCALED``).

The measurements are cached on disk next to maptools' maps (content hash of the depth map + height scale +
candidates, their WGSL code, the rays; ``maptools.cache``'s key and folder, kind ``auto_table``), measured with
``relief.probe`` (imported where it runs: the probe builds its slots from the registry, which finds this folder).
"""

from __future__ import annotations

import functools
import hashlib
import math

import numpy as np

from maptools.cache import cache_key, cached
from wgpuviewer.core.gpu import Gpu, create_texture
from wgpuviewer.core.wgsl import compose
from wgpuviewer.relief.reference import exact_hit, uv_error_texels, view_dir_from_angles
from wgpuviewer.techniques import TECHNIQUES

#: auto's relief candidates (linear steps, binary steps): POM's counts up to 32 with one or two halvings (no halving
#: is POM; a third saves 0.4 % of the table cost on the benchmark's maps, docs/techniques.md).
AUTO_RELIEF_STEPS = tuple((n, b) for n in (4, 6, 8, 12, 16, 24, 32) for b in (1, 2))
#: ``auto``'s candidates, cheapest first: (technique, parameter overrides). The shader runs each one's code
#: (basic: the entry point; parallax; pom_search with the layer count; relief_search with its linear and binary
#: steps; quadmax_search with the top offset); the probe measures each one as that technique (``measure``).
AUTO_CANDIDATES: tuple[tuple[str, dict], ...] = (
    ("basic", {}), ("parallax", {}),
    # the layer searches by their fetch bound less one (POM: layers; relief: linear + binary steps)
    *sorted((*(("pom", {"layers": n}) for n in (4, 6, 8, 12, 16, 24, 32, 48, 64)),
             *(("relief", {"linear_steps": n, "binary_steps": b}) for n, b in AUTO_RELIEF_STEPS)),
            key=lambda candidate: sum(candidate[1].values())),
    ("quadmax", {}),
)
#: auto's method ids in its table (auto.wgsl switches on them).
AUTO_METHODS = {"basic": 0, "parallax": 1, "pom": 2, "quadmax": 3, "relief": 4}
#: auto's view-angle bins: bin 0 is tan(angle) < AUTO_TAN0, bin i + 1 is [tan0 2^(i/k), tan0 2^((i+1)/k)) with
#: k = AUTO_BINS_PER_OCTAVE, up to AUTO_BINS bins (the last one open-ended): the search cost follows the ray's
#: reach tan(angle) * S * W, so the bins are even in its logarithm (about 88.7 degrees at the last edge).
AUTO_TAN0 = 2.0 ** -8
AUTO_BINS_PER_OCTAVE = 2
AUTO_BINS = 29
#: auto's error budgets (texels): 2^(AUTO_BUDGET_LOG2_MIN + j), j < AUTO_BUDGET_LEVELS; max_error picks the largest
#: one not above it.
AUTO_BUDGET_LOG2_MIN = -4
AUTO_BUDGET_LEVELS = 8
#: max_error_px's upper end (screen pixels; 0 turns the screen-space budget off).
MAX_ERROR_PX = 16.0

#: Bump when what ``measure`` computes changes (cached tables are then measured again).
VERSION = 5
#: The upper edge the table measures the open-ended last bin at (it takes every view up to 90 degrees, grazing ones
#: included): the steepest angle docs/accuracy.md reports. A candidate that meets the budget at the last bin's lower
#: edge may miss it by 100 texels here (parallax on a map that is flat but for its peaks).
LAST_BIN_TOP = 89.9
#: The parameter holding the layer count auto scales inside a bin, per candidate technique that has one.
LAYER_PARAM = {"pom": "layers", "relief": "linear_steps"}
#: The candidates (indices into AUTO_CANDIDATES) whose scaled lower-edge count is measured too: table row
#: len(AUTO_CANDIDATES) + k holds candidate SCALED[k] run with ``lower_edge_layers`` of its count.
SCALED = tuple(c for c, (name, _) in enumerate(AUTO_CANDIDATES) if name in LAYER_PARAM)
ERROR_RAYS = 1024  # independent random rays per angle for the error
TILES = 16  # screen tiles per angle for the cost
TILE = (8, 4)  # rays per tile: across x along the view azimuth, like a SIMD group of 8 x 4 pixels
TILE_SPACING = 0.75  # texels between neighbouring rays of a tile
SEED = 13
#: Time of one SIMD-tile fetch of each candidate in POM fetches, for choosing between candidates that meet a budget.
#: Measured on llvmpipe (docs/techniques.md, auto): process CPU time of 192x108 frames (brick, bricks, ridges, grass at
#: 45-80 degrees), per technique the slope of the time against the SIMD-tile fetches over settings with different
#: fetch counts (POM 16/32; relief 8+2, 12+1, 16+2; quadmax capped at 2, 4 and uncapped steps), over POM's slope:
#: relief 0.78-1.11 (median 1.05), quadmax 2.8-4.8 (median 3.16; a dependent 128-bit load, its unpacking, up to three
#: quadratic solves). A GPU run of the benchmark reports this per technique ("time per SIMD-tile fetch") to recalibrate.
COST_WEIGHTS = {"basic": 1.0, "parallax": 1.0, "pom": 1.0, "relief": 1.05, "quadmax": 3.2}
#: Columns of a measurement: p95 and p97.5 UV error (texels), mean fetches, SIMD-tile cost, capped fraction.
FIELDS = ("err_p95", "err_p975", "fetches_mean", "fetches_simd", "capped")


def edge_angles() -> np.ndarray:
    """The angles (degrees) the table is measured at: 0, the bin edges atan(tan0 2^(i / k)), i < AUTO_BINS - 1, and
    ``LAST_BIN_TOP``: bin b spans angles b and b + 1."""
    tans = AUTO_TAN0 * 2.0 ** (np.arange(AUTO_BINS - 1) / AUTO_BINS_PER_OCTAVE)
    return np.concatenate([[0.0], np.degrees(np.arctan(tans)), [LAST_BIN_TOP]])


def bin_of(angle_deg) -> np.ndarray:
    """auto.wgsl's bin index of view angles (degrees): 0 below the first edge, then one per half octave of tan."""
    tan = np.tan(np.radians(np.asarray(angle_deg, np.float64)))
    with np.errstate(divide="ignore"):
        b = np.floor(AUTO_BINS_PER_OCTAVE * np.log2(np.maximum(tan, 1e-300) / AUTO_TAN0)) + 1
    return np.clip(np.where(tan < AUTO_TAN0, 0, b), 0, AUTO_BINS - 1).astype(np.int64)


def lower_edge_layers(n: int) -> int:
    """POM's count at a bin's lower edge for table count n (auto.wgsl: ceil(n tan / tan_hi) with tan / tan_hi =
    2^(-1/k) there; n 2^(-1/k) is never an integer, so float32 rounding cannot change the ceiling)."""
    return max(1, math.ceil(n * 2.0 ** (-1.0 / AUTO_BINS_PER_OCTAVE)))


def scaled_layers(n: int, angle_deg) -> np.ndarray:
    """auto.wgsl's layer count (POM layers, relief linear steps) for table count n at view angles (degrees), in
    float64: n in bin 0 and the last bin; inside bins 1 .. AUTO_BINS - 2, ceil(n tan / tan_hi), tan_hi the bin's upper
    edge, clamped to [1, n]."""
    angle = np.asarray(angle_deg, np.float64)
    b = bin_of(angle)
    tan_hi = AUTO_TAN0 * 2.0 ** (b / AUTO_BINS_PER_OCTAVE)
    scaled = np.clip(np.ceil(n * np.tan(np.radians(angle)) / tan_hi), 1, n)
    return np.where((b >= 1) & (b < AUTO_BINS - 1), scaled, n).astype(np.int64)


def budgets() -> np.ndarray:
    return 2.0 ** (AUTO_BUDGET_LOG2_MIN + np.arange(AUTO_BUDGET_LEVELS))


def tile_rays(angle_deg: float, shape: tuple[int, int], rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """``TILES`` tiles of 8 x 4 rays at one angle: uv (n, 2), view (n, 3); ray k of tile i is i * 32 + k (row-major
    over the tile's 4 rows of 8)."""
    h, w = shape
    tw, th = TILE
    origin = rng.random((TILES, 1, 2))
    phi = rng.random(TILES) * 2 * np.pi
    along = np.stack([np.cos(phi), np.sin(phi)], -1)[:, None, :]  # the view azimuth (screen y)
    across = np.stack([-np.sin(phi), np.cos(phi)], -1)[:, None, :]  # screen x
    j, i = np.divmod(np.arange(tw * th), tw)
    offset = (i[None, :, None] * across + j[None, :, None] * along) * TILE_SPACING / np.array([w, h])
    uv = (origin + offset).reshape(-1, 2)
    view = view_dir_from_angles(np.full(TILES, angle_deg), np.degrees(phi))
    return uv, np.repeat(view, tw * th, axis=0)


def _measure(depth: np.ndarray, height_scale: float) -> np.ndarray:
    from wgpuviewer.relief.probe import probe

    rng = np.random.default_rng(SEED)
    angles = edge_angles()
    n_err, n_cost = ERROR_RAYS, TILES * TILE[0] * TILE[1]
    uv, view = [], []
    for a in angles:
        uv.append(rng.random((n_err, 2)))  # error rays: independent, all over the map
        view.append(view_dir_from_angles(np.full(n_err, a), rng.random(n_err) * 360.0))
        tiles = tile_rays(a, depth.shape, rng)  # cost rays: SIMD tiles
        uv.append(tiles[0])
        view.append(tiles[1])
    uv, view = np.concatenate(uv), np.concatenate(view)
    per_angle = n_err + n_cost
    error_rays = (np.arange(len(uv)) % per_angle) < n_err
    ref = exact_hit(depth, uv[error_rays], view[error_rays], height_scale)
    runs = [*AUTO_CANDIDATES, *(lower_edge_run(c) for c in SCALED)]
    out = np.zeros((len(runs), len(angles), len(FIELDS)))
    height = 1.0 - np.asarray(depth, np.float64)
    for c, (name, params) in enumerate(runs):
        if TECHNIQUES[name].ray_search:
            got = probe(name, height, uv, view, height_scale, **params)
            hit_uv, fetches, capped = got.uv.astype(np.float64), got.fetches.astype(np.float64), got.capped
        else:  # basic: the entry point, no fetch
            hit_uv, fetches, capped = uv, np.zeros(len(uv)), np.zeros(len(uv), bool)
        miss = capped[error_rays] | ~ref.valid
        err = np.where(miss, np.inf, uv_error_texels(hit_uv[error_rays], np.nan_to_num(ref.uv), depth.shape[::-1]))
        for a in range(len(angles)):
            e = err[a * n_err:(a + 1) * n_err]
            f = fetches[a * per_angle + n_err:(a + 1) * per_angle]
            # the SIMD-tile cost: mean over the tiles of the tile's largest fetch count
            out[c, a] = (np.percentile(e, 95), np.percentile(e, 97.5), f.mean(), f.reshape(TILES, -1).max(axis=1).mean(),
                         capped[a * per_angle:(a + 1) * per_angle].mean())
    return out


def lower_edge_run(candidate: int) -> tuple[str, dict]:
    """A SCALED candidate as auto runs it at a bin's lower edge: its layer count lowered to ``lower_edge_layers``."""
    name, params = AUTO_CANDIDATES[candidate]
    key = LAYER_PARAM[name]
    return name, {**params, key: lower_edge_layers(params[key])}


def candidates_code() -> str:
    """Hash of the candidates' WGSL (each technique file with what it includes): a cached table was measured with
    exactly this code."""
    h = hashlib.sha256()
    for name in dict.fromkeys(name for name, _ in AUTO_CANDIDATES):
        h.update(compose(TECHNIQUES[name].wgsl_file).code.encode())
    return h.hexdigest()


def measure(depth: np.ndarray, height_scale: float) -> np.ndarray:
    """The measurements (candidates + SCALED rows, angles, FIELDS) of ``depth`` (D = 1 - height) at ``height_scale``,
    from the disk cache when it holds them."""
    d = np.ascontiguousarray(depth, np.float32)
    options = {"height_scale": float(height_scale), "candidates": [[n, p] for n, p in AUTO_CANDIDATES],
               "code": candidates_code(),
               "angles": [float(a) for a in edge_angles()], "error_rays": ERROR_RAYS, "tiles": TILES, "tile": list(TILE),
               "spacing": TILE_SPACING, "seed": SEED, "version": VERSION}
    # the cache checks each entry's key and checksum: a damaged one is measured again, with a warning
    return cached("auto_table", cache_key("auto_table", d, options),
                  lambda: _measure(d.astype(np.float64), height_scale))


def choose(table: np.ndarray) -> np.ndarray:
    """Per (budget level, bin): (candidate index, error at the worse edge, weighted cost, met) as float64
    (AUTO_BUDGET_LEVELS, AUTO_BINS, 4)."""
    n = len(AUTO_CANDIDATES)
    err, simd = table[:, :, FIELDS.index("err_p975")], table[:, :, FIELDS.index("fetches_simd")]
    weights = np.array([COST_WEIGHTS[name] for name, _ in AUTO_CANDIDATES])[:, None]
    # bin b spans edges b and b + 1 (edge 0 = angle 0; the last bin's upper edge is LAST_BIN_TOP)
    lo = np.arange(AUTO_BINS)
    hi = lo + 1
    err_lo, simd_lo = err[:n, lo].copy(), simd[:n, lo].copy()
    scaled = (lo >= 1) & (lo < AUTO_BINS - 1)  # bins whose lower edge runs the scaled count (scaled_layers)
    for k, c in enumerate(SCALED):
        err_lo[c, scaled] = err[n + k, lo[scaled]]
        simd_lo[c, scaled] = simd[n + k, lo[scaled]]
    bin_err = np.maximum(err_lo, err[:n, hi])
    bin_cost = weights * np.maximum(simd_lo, simd[:n, hi])
    out = np.zeros((AUTO_BUDGET_LEVELS, AUTO_BINS, 4))
    for j, budget in enumerate(budgets()):
        for b in range(AUTO_BINS):
            ok = np.flatnonzero(bin_err[:, b] <= budget)
            c = int(ok[np.argmin(bin_cost[ok, b])]) if ok.size else int(np.argmin(bin_err[:, b]))
            out[j, b] = (c, bin_err[c, b], bin_cost[c, b], float(ok.size > 0))
    return out


def texels(table: np.ndarray) -> np.ndarray:
    """The table texture's texels, float32 (AUTO_BUDGET_LEVELS, AUTO_BINS, 4): candidate index, method id (auto.wgsl),
    the method's parameter (POM layers, relief linear steps, quadmax top_offset), relief's binary steps (else 0)."""
    choice = choose(table)
    out = np.zeros(choice.shape, np.float32)
    for j in range(AUTO_BUDGET_LEVELS):
        for b in range(AUTO_BINS):
            name, params = AUTO_CANDIDATES[int(choice[j, b, 0])]
            resolved = {**TECHNIQUES[name].defaults(), **params}
            value = resolved.get(LAYER_PARAM.get(name, "top_offset"), 0)
            out[j, b] = (choice[j, b, 0], AUTO_METHODS[name], value, resolved.get("binary_steps", 0))
    return out


def table_texture(gpu: Gpu, table: np.ndarray, label: str):
    return create_texture(gpu, [texels(table)], "rgba32float", label)


def fragment_budget(max_error: float, max_error_px: float, footprint, view) -> np.ndarray:
    """auto.wgsl's auto_budget in float64: per ray the error budget in texels, max(max_error, max_error_px |det J| /
    |adj(J) d|) where max_error_px > 0 and det J > 0 (else max_error). ``footprint``: (N, 4) the pixel in texels
    (J's columns: texels per pixel along screen x, then y); ``view``: (N, 3) tangent-space V, whose xy (in texels)
    gives d, the direction every hit of the ray lies along."""
    j = np.asarray(footprint, np.float64).reshape(-1, 4)
    along = np.asarray(view, np.float64)[:, :2] * np.ones((len(j), 1))
    norm = np.linalg.norm(along, axis=1, keepdims=True)
    d = np.where(norm > 1e-15, along / np.where(norm > 0, norm, 1.0), [1.0, 0.0])
    det = np.abs(j[:, 0] * j[:, 3] - j[:, 1] * j[:, 2])
    adj = np.stack([j[:, 3] * d[:, 0] - j[:, 2] * d[:, 1], j[:, 0] * d[:, 1] - j[:, 1] * d[:, 0]], -1)
    screen = max_error_px * det / np.maximum(np.linalg.norm(adj, axis=1), 1e-300)
    return np.maximum(max_error, np.where((max_error_px > 0) & (det > 0), screen, 0.0))


def budget_level(max_error: float) -> int:
    """auto.wgsl's budget level for a budget (texels): the largest budget 2^(min + j) not above it."""
    return int(np.clip(math.floor(math.log2(max_error)) - AUTO_BUDGET_LOG2_MIN, 0, AUTO_BUDGET_LEVELS - 1))


def candidate_label(index: int) -> str:
    name, params = AUTO_CANDIDATES[index]
    return " ".join([name, *(f"{k}={v}" for k, v in params.items())])


def describe(table: np.ndarray, max_error: float) -> list[str]:
    """One line per run of bins with the same choice at ``max_error``: angle range, candidate, worst p97.5, cost."""
    level = budget_level(max_error)
    choice = choose(table)[level]
    edges = edge_angles()
    lines, b = [], 0
    while b < AUTO_BINS:
        end = b
        while end + 1 < AUTO_BINS and choice[end + 1, 0] == choice[b, 0]:
            end += 1
        lo = edges[b]
        hi = f"{edges[end + 1]:.1f}°" if end + 1 < AUTO_BINS else "90°"
        worst = float(choice[b:end + 1, 1].max())
        met = "" if choice[b:end + 1, 3].all() else " (budget not met)"
        label = candidate_label(int(choice[b, 0]))
        name, params = AUTO_CANDIDATES[int(choice[b, 0])]
        if name in LAYER_PARAM and b >= 1 and end < AUTO_BINS - 1:  # scaled with tan inside each bin
            key = LAYER_PARAM[name]
            scaled = {**params, key: f"{lower_edge_layers(params[key])}-{params[key]}"}
            label = " ".join([name, *(f"{k}={v}" for k, v in scaled.items())]) + " by angle"
        lines.append(f"{lo:.1f}-{hi}: {label}, p97.5 <= {worst:.3g} texel, "
                     f"cost <= {float(choice[b:end + 1, 2].max()):.3g}{met}")
        b = end + 1
    return lines


def methods_picked(table: np.ndarray, max_error: float, max_error_px: float) -> tuple[str, ...]:
    """The methods (AUTO_METHODS names, in their order) the shader can run with ``table``: its choices at
    ``max_error``'s budget level in every bin, and with a screen-space budget (``max_error_px`` > 0: a fragment's
    budget is max_error or more, ``fragment_budget``) at every level above it too."""
    level = budget_level(max_error)
    levels = range(level, AUTO_BUDGET_LEVELS) if max_error_px > 0 else (level,)
    chosen = {int(c) for c in choose(table)[list(levels), :, 0].ravel()}
    names = {AUTO_CANDIDATES[c][0] for c in chosen}
    return tuple(name for name in AUTO_METHODS if name in names)


def paths_used(material, params: dict) -> tuple[str, ...]:
    """auto's ``Technique.paths_used``: the methods its table for ``material`` (a scene material: its depth map at its
    own height scale, as its ``auto_table`` slot is built) picks at ``params``; its module compiles only those."""
    return _paths(material, budget_level(params["max_error"]), params["max_error_px"] > 0)


@functools.lru_cache(maxsize=256)
def _paths(material, level: int, screen: bool) -> tuple[str, ...]:
    """``paths_used`` by what decides it, remembered: the renderer asks on every draw, and reading the table hashes
    the depth map (tens of ms for 512²)."""
    from wgpuviewer.relief.material_textures import depth_data

    table = measure(depth_data(material), material.height_scale)
    return methods_picked(table, float(budgets()[level]), 1.0 if screen else 0.0)


def panel_lines(materials: dict, params: dict) -> list[str]:
    """What auto chooses per view-angle range at its ``max_error`` on each material (name -> scene material), from
    its measured table: the viewer's info panel shows these lines (the layers view paints the candidate numbers)."""
    from wgpuviewer.relief.material_textures import depth_data

    max_error = params["max_error"]
    lines = [f"auto at max_error {max_error:g}: budget {budgets()[budget_level(max_error)]:g} texel"]
    for name, material in materials.items():
        lines.append(f"{name}:")
        lines += [f"  {line}" for line in describe(measure(depth_data(material), material.height_scale), max_error)]
    return lines
