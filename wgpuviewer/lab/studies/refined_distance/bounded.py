"""The refined map bounded: on small maps (photograph crops, builtins, the generated plate and grille) the fetches of
the distance tracer (the numpy twin) with the exact-visibility map (``exact``: the least free path over sampled
visible rays, an estimate from above of what the paper's idea allows) beside the product's maps: ``distance``, the
single cone and the 4 x 8 bins with no condition and with the conservative cut (the paper's condition as maptools
bakes it). Per map also the check of the exact map's sampling (``exact.check``) and how its value gain over the plain
map converged with the rays. ``bounded.csv`` and ``bounded_maps.csv``; the report's section.
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from maptools.kinds.distance_refined.slot import REFINED_BANDS, REFINED_MAX_ANGLE, REFINED_SECTORS
from maptools.volume.slot import DISTANCE_SLICES
from wgpuviewer.lab.harness.table import Column, Table
from wgpuviewer.relief.accuracy import simd_tile_cost

from . import exact, reliefs
from .tracer import trace
from .variants import CONDITION_PAIRS, PLAIN, PRODUCT, SINGLE_CONE

#: The map classes the conclusion speaks of.
CLASSES = {"brick": "photographs", "grass": "photographs", "gravel": "photographs", "bricks": "builtins",
           "bumps": "builtins", "ridges": "builtins", "wall": "builtins", "plate": "perforated",
           "grille": "perforated"}
PAPER, BINNED_CUT = CONDITION_PAIRS[0][0], CONDITION_PAIRS[1][0]
EXACT_SINGLE, EXACT_BINNED = "single cone, exact visibility", f"{PRODUCT}, exact visibility"
#: The product's variants measured here, then the two exact ones (their names hold "exact visibility").
PRODUCT_VARIANTS = (PLAIN, SINGLE_CONE, PAPER, PRODUCT, BINNED_CUT)
#: A twin's hit farther than this (texels along the ray) from the float64 exact hit: the map let the ray pass.
PASS_TEXELS = 0.01

TABLE = Table("refined-distance bounded", (
    Column("heightmap", str), Column("class", str), Column("size", str, "texels, WxH"),
    Column("angle", float, "degrees"), Column("variant", str),
    Column("fetches_mean", float, "fetches per pixel (numpy twin)"), Column("fetches_simd", float, "per 8x4 tile"),
    Column("passed", float, "of the pixels: the twin's hit is not the exact hit (the map let the ray pass)"),
))
MAPS_TABLE = Table("refined-distance exact maps", (
    Column("heightmap", str), Column("class", str), Column("variant", str),
    Column("rays_per_texel", int, "random visible rays per texel and bin"),
    Column("batches", int, "of rays_per_texel / batches each"), Column("build_s", float, "seconds"),
    Column("gain_first", float, "mean stored value - plain value over the voxels, texels, after the first batch"),
    Column("gain", float, "the same after all batches (it falls towards the exact value as rays are added)"),
    Column("gain_cut", float, "the same for the product's map with the conservative cut"),
    Column("check_rays", int, "fresh random visible rays"),
    Column("check_exceeded", float, "of the check rays: a stored value exceeds the ray's free path by > 0.001"),
    Column("check_p99", float, "texels: 99th percentile of the excess"),
    Column("check_max", float, "texels: largest excess"),
))


def height(name: str, size: int) -> np.ndarray:
    """float32 (size, size) in [0, 1]: a crop from the middle of a scikit-image photograph (full resolution), a
    builtin or a generated relief."""
    if name in reliefs.NAMES:
        return reliefs.GENERATORS[name](size)
    if CLASSES.get(name) == "photographs":
        import skimage.data

        grey = np.asarray(getattr(skimage.data, name)(), np.float32) / 255.0
        j, i = (grey.shape[0] - size) // 2, (grey.shape[1] - size) // 2
        return np.ascontiguousarray(grey[j:j + size, i:i + size])
    from wgpuviewer.textures import builtin_height

    return builtin_height(name, (size, size)).astype(np.float32)


def heightmap(name: str, size: int, workdir: Path):
    """The bench's HeightMap of ``height(name, size)``, written to ``workdir`` as .npy for the view's scene."""
    from wgpuviewer.lab.bench.view import HeightMap

    h = height(name, size)
    path = Path(workdir) / f"bounded_{name}_{size}.npy"
    np.save(path, h)
    texture = '"' + str(path).replace("\\", "\\\\").replace('"', '\\"') + '"'
    return HeightMap(name, h, texture, f"{name} {size}x{size} (studies.refined_distance.bounded)")


def exact_maps(h: np.ndarray, floors: dict[str, np.ndarray], height_scale: float, rays_per_texel: int,
               batches: int):
    """The exact-visibility maps (single cone (2, ...) and 4 x 8 bins (33, ...)), each floored at ``floors[name]``
    (the product's map of its bins with the cut), with its mean gain over the plain map after the first batch and
    after all, and the seconds taken. Each batch: rays_per_texel fresh rays."""
    t0 = time.perf_counter()
    raw, gains = None, []

    def maps(r):
        return {EXACT_SINGLE: exact.stored(exact.single_cone(r), floors[EXACT_SINGLE]),
                EXACT_BINNED: exact.stored(r, floors[EXACT_BINNED])}
    for b in range(batches):
        got = exact.raw_bins(h, DISTANCE_SLICES, height_scale, REFINED_SECTORS, REFINED_BANDS, REFINED_MAX_ANGLE,
                             rays_per_texel, seed=b)
        raw = got if raw is None else np.minimum(raw, got)
        if b in (0, batches - 1):
            gains.append({v: float((m[:-1] - m[-1]).mean()) for v, m in maps(raw).items()})
    seconds = time.perf_counter() - t0
    return maps(raw), gains[0], gains[-1], seconds


def measure(name: str, suite, build, on_rows=lambda rows, maps: None) -> tuple[list[dict], list[dict]]:
    """Rows of TABLE and MAPS_TABLE for one map at ``suite.exact_size``². ``build(variant_name, height)`` gives a
    product variant's volumes as the tracer reads them (the study's cached build)."""
    import tempfile

    from wgpuviewer.lab.bench.view import HEIGHT_SCALE, make_view
    from wgpuviewer.relief.reference import exact_hit

    with tempfile.TemporaryDirectory(prefix="wgpuviewer-bounded-") as workdir:
        hm = heightmap(name, suite.exact_size, Path(workdir))
        views = [make_view(hm, a, suite.resolution) for a in suite.exact_angles]
    h = hm.height
    depth = 1.0 - h.astype(np.float64)
    volumes = {v: build(v, h) for v in PRODUCT_VARIANTS}
    exacts, first, last, seconds = exact_maps(h, {EXACT_SINGLE: volumes[PAPER], EXACT_BINNED: volumes[BINNED_CUT]},
                                              HEIGHT_SCALE, suite.exact_rays, suite.exact_batches)
    volumes.update(exacts)
    base = {"heightmap": name, "class": CLASSES.get(name, "other")}
    maps = []
    for variant, (sectors, bands), cut in ((EXACT_SINGLE, (1, 1), PAPER), (EXACT_BINNED, (REFINED_SECTORS,
                                                                                          REFINED_BANDS), BINNED_CUT)):
        excess = exact.check(h, volumes[variant], HEIGHT_SCALE, sectors, bands, REFINED_MAX_ANGLE,
                             max(1, suite.exact_checks // (sectors * bands)), seed=10_000)
        excess = excess[np.isfinite(excess)]
        maps.append({**base, "variant": variant, "rays_per_texel": suite.exact_rays * suite.exact_batches,
                     "batches": suite.exact_batches,
                     "build_s": seconds, "gain_first": first[variant], "gain": last[variant],
                     "gain_cut": float((volumes[cut][:-1] - volumes[cut][-1]).mean()), "check_rays": int(excess.size),
                     "check_exceeded": float((excess > 1e-3).mean()),
                     "check_p99": float(np.percentile(excess, 99)), "check_max": float(excess.max())})
    rows = []
    for view in views:
        uv, v = view.uv0.reshape(-1, 2), view.v_ts.reshape(-1, 3)
        ref = exact_hit(depth, uv, v, HEIGHT_SCALE).t
        per_t = h.shape[1] * HEIGHT_SCALE * np.linalg.norm(v, axis=1) / v[:, 2]
        for variant, vol in volumes.items():
            binned = vol.shape[0] > 2
            bins = {"sectors": REFINED_SECTORS if binned else 1, "bands": REFINED_BANDS if binned else 1,
                    "max_angle": REFINED_MAX_ANGLE} if vol.ndim == 4 else {}
            got = trace(depth, vol, uv, v, HEIGHT_SCALE, **bins)
            fetches = got.fetches.reshape(view.uv0.shape[:2])
            passed = ~(np.abs(got.t - ref) * per_t <= PASS_TEXELS)
            rows.append({**base, "size": f"{h.shape[1]}x{h.shape[0]}", "angle": view.angle, "variant": variant,
                         "fetches_mean": float(fetches.mean()), "fetches_simd": simd_tile_cost(fetches),
                         "passed": float(passed.mean())})
    on_rows(rows, maps)
    return rows, maps


# -- the report ------------------------------------------------------------------------------------------------------

#: The report's columns: (label, variant), each as its change of mean fetches against `distance` (PLAIN).
COLUMNS = (("single cone", SINGLE_CONE), ("paper's map (cut)", PAPER), ("single cone, exact", EXACT_SINGLE),
           ("4 x 8", PRODUCT), ("4 x 8, cut", BINNED_CUT), ("4 x 8, exact", EXACT_BINNED))


def changes(rows: list[dict]) -> dict[tuple[str, float, str], float]:
    """(map, angle, variant) -> mean fetches over `distance`'s on the same view, minus 1."""
    plain = {(r["heightmap"], r["angle"]): r["fetches_mean"] for r in rows if r["variant"] == PLAIN}
    return {(r["heightmap"], r["angle"], r["variant"]): r["fetches_mean"] / plain[r["heightmap"], r["angle"]] - 1.0
            for r in rows if plain.get((r["heightmap"], r["angle"]))}


def by_class(rows: list[dict]) -> dict[str, dict[str, list[float]]]:
    """class -> variant -> the changes against `distance` over its maps and angles."""
    cls = {r["heightmap"]: r["class"] for r in rows}
    out: dict[str, dict[str, list[float]]] = {}
    for (name, _, variant), c in changes(rows).items():
        out.setdefault(cls[name], {}).setdefault(variant, []).append(c)
    return out


def share(cut: list[float], bound: list[float]) -> float:
    """The part of the exact bound's mean saving the conservative cut gets (NaN where the bound saves nothing)."""
    b = -float(np.mean(bound))
    return -float(np.mean(cut)) / b if b > 1e-9 else float("nan")


def _pct(values: list[float]) -> str:
    lo, hi, mean = 100 * min(values), 100 * max(values), 100 * float(np.mean(values))
    return f"{mean:+.1f} % ({lo:+.1f} to {hi:+.1f})"


def section(rows: list[dict], maps: list[dict]) -> list[str]:
    """The report's section: per class and per map the changes against `distance`, and the sampling's check."""
    if not rows:
        return []
    size, angles = rows[0]["size"], sorted({r["angle"] for r in rows})
    rays = maps[0]["rays_per_texel"] if maps else 0
    lines = ["## The refined map bounded: exact visibility", "",
             f"Maps {size} (`studies/refined_distance/bounded.py`: crops from the middle of the photographs, builtins, "
             f"the generated plate and grille), the benchmark's views at {', '.join(f'{a:g}' for a in angles)}°, the "
             "numpy twin, every fetch to the hit; changes of mean fetches against `distance`, mean over the class's "
             "maps and angles (least to most). *Exact*: the least free path over random rays of the bin that reach "
             f"the voxel unblocked from the top, cast against the float64 surface ({rays} per texel and bin; "
             "`studies/refined_distance/exact.py`): an estimate from above of what the paper's idea allows, so its "
             "saving bounds the idea's; *cut*: the product's conservative visibility cut. *passed*: pixels whose hit "
             "with the exact map is not the exact hit (where sampling overestimated a value).", "",
             "| class | " + " | ".join(label for label, _ in COLUMNS) + " | cut's share of the exact saving: single "
             "cone / 4 x 8 | passed (exact: single / 4 x 8) |", "|---|" + "---|" * (len(COLUMNS) + 2)]
    passed = {}
    for r in rows:
        passed.setdefault((r["class"], r["variant"]), []).append(r["passed"])
    for cls, d in by_class(rows).items():
        cells = [_pct(d[v]) if v in d else "-" for _, v in COLUMNS]
        cells.append(" / ".join(f"{share(d[cut], d[bound]) + 0.0:.0%}" for cut, bound in ((PAPER, EXACT_SINGLE),
                                                                                        (BINNED_CUT, EXACT_BINNED))))
        cells.append(" / ".join(f"{100 * max(passed[cls, v]):.2f} %" for v in (EXACT_SINGLE, EXACT_BINNED)))
        lines.append(f"| {cls} | " + " | ".join(cells) + " |")
    lines += ["", "Per map and angle (change of mean fetches against `distance`):", "",
              "| map | angle | " + " | ".join(label for label, _ in COLUMNS) + " |", "|---|---|" + "---|" * len(COLUMNS)]
    ch = changes(rows)
    for name, angle in dict.fromkeys((r["heightmap"], r["angle"]) for r in rows):
        lines.append(f"| {name} | {angle:g}° | " + " | ".join(
            f"{100 * ch[name, angle, v]:+.1f} %" if (name, angle, v) in ch else "-" for _, v in COLUMNS) + " |")
    lines += ["", "The exact maps' sampling: mean value over the plain map's (texels, over all voxels) after the first "
              "batch of rays and after all (falling towards the exact value as rays are added), the conservative cut's "
              "for comparison; fresh random visible rays of every bin: the part whose free path at some voxel they "
              "cross is below the stored value by more than 0.001 texel, the 99th percentile and the largest excess.",
              "", "| map | map variant | gain: first batch → all | cut's gain | check rays | exceeded | p99 | max |",
              "|---|---|---|---|---|---|---|---|"]
    for m in maps:
        lines.append(f"| {m['heightmap']} | {m['variant']} | {m['gain_first']:.3f} → {m['gain']:.3f} | "
                     f"{m['gain_cut']:.3f} | {m['check_rays']} | {100 * m['check_exceeded']:.2f} % | "
                     f"{m['check_p99']:.3f} | {m['check_max']:.2f} |")
    return lines + [""]
