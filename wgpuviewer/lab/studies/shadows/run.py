"""The shadow study's measurement: suites, rows, results.csv, report.md and shadows.png.

Rays: a grid of entry points over the whole map (``Suite.grid``, one ray per cell, neighbours in 8 x 4 SIMD tiles as
pixels are) at VIEW_ANGLE from the normal. Each ray's exact first hit (``reference.exact_hit``) is shaded by a
directional light at each elevation (azimuth LIGHT_AZIMUTH from the view's): its float64 shadow
(``reference.shadow``) is the truth. Per technique the GPU shadow (``probe.shadow_probe``: the renderer's WGSL) is
taken twice: at the exact hit (the shadow ray's own error) and at the technique's own view hit (``probe.probe``; what
the renderer draws: both rays' errors). Timing (``relief.draw_timing``): frames of a brick floor, open and half hidden
behind a wall drawn first, with shadows off, hard, soft and ``depth_offset`` on drawn side by side (the draw's
overrides, round robin).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from wgpuviewer.core.gpu import get_gpu
from wgpuviewer.core.io import write_bytes
from wgpuviewer.lab.bench.view import load_heightmap
from wgpuviewer.lab.harness import suite as harness_suite
from wgpuviewer.lab.harness.header import Clock, Header
from wgpuviewer.lab.harness.plots import MISSING, pyplot, save_png
from wgpuviewer.lab.harness.table import Column, Table
from wgpuviewer.relief import reference as ref
from wgpuviewer.relief.accuracy import LIGHT_AZIMUTH, measure_shadows, shadowing_techniques, simd_tile_cost
from wgpuviewer.relief.draw_timing import time_draws
from wgpuviewer.relief.renderer import Renderer
from wgpuviewer.scene import parse_scene

TITLE = "Self-shadowing: hard and soft shadows of every ray-search technique against the float64 reference"
VIEW_ANGLE = 45.0  # degrees from the normal, azimuth 0 (lights at accuracy.LIGHT_AZIMUTH: from the side, towards it)
HEIGHT_SCALE = 0.08  # relief depth in uv units


@dataclass(frozen=True)
class Suite(harness_suite.Suite):
    heightmaps: tuple[str, ...]
    techniques: tuple[str, ...] | None  # None: every shadowing technique
    elevations: tuple[float, ...]
    grid: tuple[int, int]  # rays (columns, rows) over the map
    builtin_size: int
    real_size: int = 0
    timing_size: tuple[int, int] = (160, 90)  # frame of the timed draws
    timing_frames: int = 5  # frames per draw


SUITES = harness_suite.suites(
    Suite("smoke", ("bumps", "wall"), ("pom", "maxmip"), (30.0, 60.0), (32, 32), builtin_size=48,
          timing_size=(64, 36), timing_frames=3),
    Suite("full", ("brick", "bricks", "bumps", "spike", "step", "wall", "checker"), None, (30.0, 45.0, 60.0, 80.0),
          (96, 96), builtin_size=128, real_size=256, timing_size=(480, 270), timing_frames=20),
)

RESULTS = Table("shadow study results", [
    Column("heightmap", str), Column("technique", str), Column("elevation", float, "degrees"),
    Column("rays", int, "rays with a valid reference"),
    Column("ref_lit", float, "fraction of the rays the reference lights"),
    Column("hard_wrong", float, "fraction with the wrong hard state, at the exact hit"),
    Column("hard_wrong_own_hit", float, "fraction with the wrong hard state, at the technique's own view hit"),
    Column("soft_diff", float, "mean |visibility - reference|, at the exact hit"),
    Column("soft_diff_own_hit", float, "mean |visibility - reference|, at the technique's own view hit"),
    Column("hard_fetches", float, "depth fetches per shadow ray"),
    Column("hard_fetches_simd", float, "per 8x4 tile, the slowest lane's shadow-ray fetches"),
    Column("soft_fetches", float, "depth fetches per soft estimate"),
    Column("view_fetches", float, "depth fetches per view ray"),
    Column("capped", float, "fraction of shadow rays flagged capped"),
])


TIMING = Table("shadow study timing", [
    Column("scene", str, "open: the floor alone; occluded: a wall drawn first hides part of it"),
    Column("technique", str), Column("variant", str, "plain, shadows=hard|soft or depth_offset=on"),
    Column("ms", float, "median ms per frame (software adapter: only ratios)"),
    Column("ratio", float, "ms / the same scene and technique's plain draw (shadows off, depth_offset off)"),
    Column("hidden", float, "fraction of the floor's pixels behind the wall (the fragments early depth testing skips)"),
])
TIMING_TECHNIQUES = ("pom", "maxmip")
#: The timed variants: the draw's overrides (shadows, depth_offset) on a material that has neither.
TIMING_VARIANTS = {"plain": {}, "shadows=hard": {"shadows": "hard"}, "shadows=soft": {"shadows": "soft"},
                   "depth_offset=on": {"depth_offset": True}}
#: The timed scene: the default scene's brick floor (FLOOR), seen as it sees it, with its directional light; in the
#: occluded scene a wall (OCCLUDER) is listed, so drawn, before the floor, standing between it and the camera.
TIMING_SCENE = """
[scene]
techniques = ["pom", "maxmip"]
[camera]
position = [0.0, 1.4, 3.2]
target = [0.0, 0.0, 0.0]
fov = 55
[[lights]]
type = "directional"
direction = [-0.4, -1.0, -0.5]
[materials.bricks]
albedo = {{ builtin = "bricks", size = [512, 512] }}
height = {{ builtin = "bricks", size = [512, 512] }}
height_scale = 0.06
uv_scale = [2.0, 2.0]
[materials.grey]
albedo = [0.5, 0.5, 0.5]
{objects}
"""
FLOOR = """[[objects]]
type = "plane"
material = "bricks"
size = [4.0, 4.0]"""
OCCLUDER = """[[objects]]
type = "box"
material = "grey"
size = [4.0, 1.2, 0.1]
position = [0.0, 0.6, 1.0]"""


def timing(gpu, suite: Suite) -> list[dict]:
    """Frame times per scene (open, occluded) and technique of every TIMING_VARIANTS draw, round robin in one renderer
    (``relief.draw_timing``), as ratios to the plain draw. Writing the hit's depth (depth_offset) turns off early depth
    testing: behind the wall the floor's fragments then run their whole search before the depth test drops them."""
    rows = []
    for scene_name, objects in (("open", FLOOR), ("occluded", OCCLUDER + "\n" + FLOOR)):
        renderer = Renderer(parse_scene(TIMING_SCENE.format(objects=objects)), gpu)
        hidden = _hidden_share(gpu, suite.timing_size) if scene_name == "occluded" else 0.0
        for technique in TIMING_TECHNIQUES:
            draws = [renderer.config(technique, **overrides) for overrides in TIMING_VARIANTS.values()]
            results = time_draws(renderer, draws, suite.timing_size, suite.timing_frames, 1).results
            base = results[0].median_ms
            rows += [{"scene": scene_name, "technique": technique, "variant": variant, "ms": t.median_ms,
                      "ratio": t.median_ms / base, "hidden": hidden}
                     for variant, t in zip(TIMING_VARIANTS, results)]
    return rows


def _hidden_share(gpu, size: tuple[int, int]) -> float:
    """The fraction of the floor's covered pixels that the wall covers (each rendered alone, basic)."""
    floor, wall = (Renderer(parse_scene(TIMING_SCENE.format(objects=o)), gpu).render("basic", size).covered
                   for o in (FLOOR, OCCLUDER))
    return float((floor & wall).sum() / max(floor.sum(), 1))


def rays(grid: tuple[int, int]) -> tuple[np.ndarray, np.ndarray]:
    """Entry uv (H*W, 2) at the grid's cell centres and the one view direction (3,)."""
    w, h = grid
    u, v = np.meshgrid((np.arange(w) + 0.5) / w, (np.arange(h) + 0.5) / h)
    return np.stack([u, v], -1).reshape(-1, 2), ref.view_dir_from_angles(VIEW_ANGLE, 0.0)


def measure(height: np.ndarray, name: str, techniques, elevations, grid, progress=None) -> tuple[list[dict], dict]:
    """The rows of one height map, and the masks of the first elevation for the picture (name -> (H, W) bool)."""
    uv, view = rays(grid)
    ok, measured = measure_shadows(height, techniques, elevations, uv, view, HEIGHT_SCALE, progress=progress)
    shape = (grid[1], grid[0])
    covered = _grid(np.ones(ok.sum(), bool), ok, shape)
    first = [m for m in measured if m.elevation == elevations[0]]
    masks = {"reference": _grid(first[0].ref_lit_rays, ok, shape)} if first else {}
    masks.update({m.technique: _grid(m.lit, ok, shape) for m in first})
    rows = [{
        "heightmap": name, "technique": m.technique, "elevation": m.elevation, "rays": m.rays, "ref_lit": m.ref_lit,
        "hard_wrong": m.hard_wrong, "hard_wrong_own_hit": m.hard_wrong_own_hit, "soft_diff": m.soft_diff,
        "soft_diff_own_hit": m.soft_diff_own_hit, "hard_fetches": float(m.hard_fetches.mean()),
        "hard_fetches_simd": simd_tile_cost(_grid(m.hard_fetches, ok, shape), covered=covered),
        "soft_fetches": m.soft_fetches, "view_fetches": m.view_fetches, "capped": m.capped,
    } for m in measured]
    return rows, masks


def _grid(values: np.ndarray, ok: np.ndarray, shape) -> np.ndarray:
    """Per-valid-ray ``values`` back on the ray grid (rays without a valid reference: 0 / False)."""
    full = np.zeros(ok.shape, values.dtype)
    full[ok] = values
    return full.reshape(shape)


def run(out: Path, suite_name: str = "full", heightmaps=None, techniques=None, elevations=None, backend=None,
        progress: bool = True, command: str = "wgpuviewer shadows") -> list[dict]:
    suite = harness_suite.pick(SUITES, suite_name)
    names = tuple(heightmaps or suite.heightmaps)
    chosen = tuple(techniques or suite.techniques or shadowing_techniques())
    angles = tuple(elevations or suite.elevations)
    gpu = get_gpu(backend, quiet=True)
    clock = Clock()
    from tqdm import tqdm

    rows, pictures = [], {}
    with tqdm(total=len(names) * len(chosen) * len(angles), desc="shadows", disable=not progress or None,
              leave=False) as bar:
        for name in names:
            heightmap = load_heightmap(name, suite.builtin_size, out, suite.real_size)
            got, masks = measure(heightmap.height, name, chosen, angles, suite.grid, lambda: bar.update(1))
            rows += got
            pictures[name] = masks
    times = timing(gpu, suite)
    RESULTS.write(out / "results.csv", rows)
    TIMING.write(out / "timing.csv", times)
    header = Header(TITLE, command, gpu.summary, suite.name, clock.started, clock.seconds)
    picture = _picture(out, rows, pictures, angles[0])
    write_bytes(out / "report.md", report(header, rows, picture, suite, times).encode("utf-8"))
    return rows


def report(header: Header, rows: list[dict], picture: str | None, suite: Suite, times: list[dict]) -> str:
    lines = header.lines() + [
        f"- rays: a {suite.grid[0]}x{suite.grid[1]} grid over each map at {VIEW_ANGLE:g} degrees from the normal; "
        f"light azimuth {LIGHT_AZIMUTH:g} degrees from the view's; height_scale {HEIGHT_SCALE:g}",
        f"- hard-shadow tolerance {ref.SHADOW_TOLERANCE_TEXELS:g} texel of travel; soft estimate "
        f"{ref.SOFT_SHADOW_SAMPLES} samples, penumbra {ref.SOFT_SHADOW_PENUMBRA:g} (tangent); reference every "
        f"{ref.SOFT_REFERENCE_STEP_TEXELS:g} texel (docs/shadows.md)",
        "",
        "`hard wrong`: fraction of rays whose hard shadow state differs from the float64 reference at the exact hit "
        "(the shadow ray alone); `own hit`: the same with the shadow cast from the technique's own view hit (what "
        "the renderer draws). `soft diff`: mean |visibility - reference| (at the exact hit the soft estimate does not "
        "depend on the technique: its samples are plain depth reads). Fetches: depth fetches per shadow ray, "
        "mean and SIMD-tile (per 8x4 tile of neighbouring rays, the slowest lane's). Means over maps and elevations.",
        "",
        "| technique | hard wrong | own hit | soft diff | own hit | hard fetches | SIMD-tile | soft fetches | "
        "view fetches | capped |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    techniques = list(dict.fromkeys(r["technique"] for r in rows))
    for t in techniques:
        sel = [r for r in rows if r["technique"] == t]

        def mean(key, sel=sel):
            return float(np.mean([r[key] for r in sel]))

        lines.append(f"| `{t}` | {mean('hard_wrong'):.2%} | {mean('hard_wrong_own_hit'):.2%} | "
                     f"{mean('soft_diff'):.4f} | {mean('soft_diff_own_hit'):.4f} | {mean('hard_fetches'):.1f} | "
                     f"{mean('hard_fetches_simd'):.1f} | {mean('soft_fetches'):.1f} | {mean('view_fetches'):.1f} | "
                     f"{mean('capped'):.2%} |")
    elevations = sorted({r["elevation"] for r in rows})
    lines += ["", "Hard wrong at the exact hit / at the own hit, by light elevation (mean over maps):", "",
              "| technique | " + " | ".join(f"{e:g}°" for e in elevations) + " |",
              "|---|" + "---|" * len(elevations)]
    for t in techniques:
        cells = []
        for e in elevations:
            sel = [r for r in rows if r["technique"] == t and r["elevation"] == e]
            cells.append(f"{np.mean([r['hard_wrong'] for r in sel]):.2%} / "
                         f"{np.mean([r['hard_wrong_own_hit'] for r in sel]):.2%}")
        lines.append(f"| `{t}` | " + " | ".join(cells) + " |")
    maps = list(dict.fromkeys(r["heightmap"] for r in rows))
    lines += ["", "Lit fraction of the reference per map (mean over elevations): " + ", ".join(
        f"{m} {np.mean([r['ref_lit'] for r in rows if r['heightmap'] == m]):.0%}" for m in maps) + "."]
    hidden = max(r["hidden"] for r in times)
    lines += ["", f"Frame times of the default scene's brick floor at {suite.timing_size[0]}x{suite.timing_size[1]} "
              f"(`relief.draw_timing`, median of {suite.timing_frames} frames, the variants drawn round robin), open and "
              f"with a wall drawn first that hides {hidden:.0%} of it, as ratios to the same scene and technique's "
              "plain draw:", "",
              "| scene | technique | " + " | ".join(TIMING_VARIANTS) + " |", "|---|---|" + "---|" * len(TIMING_VARIANTS)]
    for scene_name in dict.fromkeys(r["scene"] for r in times):
        for t in TIMING_TECHNIQUES:
            cells = [f"{r['ratio']:.2f}" for r in times if r["technique"] == t and r["scene"] == scene_name]
            lines.append(f"| {scene_name} | `{t}` | " + " | ".join(cells) + " |")
    lines += ["", f"![hard shadow errors and costs]({picture})" if picture else MISSING, ""]
    return "\n".join(lines)


def _picture(out: Path, rows: list[dict], pictures: dict, elevation: float) -> str | None:
    """shadows.png: hard-shadow errors by elevation, fetches per technique, and the first map's hard shadows at the
    first elevation: the reference's, and those of the technique with the most wrong rays there and the one with the
    fewest (wrong rays in red)."""
    with pyplot() as plt:
        if plt is None:
            return None
        techniques = list(dict.fromkeys(r["technique"] for r in rows))
        first = next(iter(pictures))
        masks = pictures[first]
        fig = plt.figure(figsize=(13, 9))
        grid = fig.add_gridspec(2, 6, hspace=0.45, wspace=0.6)
        errors = fig.add_subplot(grid[0, :3])
        costs = fig.add_subplot(grid[0, 3:])
        elevations = sorted({r["elevation"] for r in rows})
        colors = plt.get_cmap("tab20").colors
        for i, t in enumerate(techniques):
            errors.plot(elevations, [100 * np.mean([r["hard_wrong_own_hit"] for r in rows
                                                    if r["technique"] == t and r["elevation"] == e])
                                     for e in elevations], marker="os^v"[i % 4], color=colors[i % 20], label=t)
        errors.set_xlabel("light elevation (degrees)")
        errors.set_ylabel("wrong hard shadow, own hit (% of rays)")
        errors.grid(True)
        errors.legend(fontsize=7, ncol=2)
        x = np.arange(len(techniques))
        for offset, key, label in ((-0.2, "hard_fetches", "mean"), (0.2, "hard_fetches_simd", "SIMD-tile")):
            costs.bar(x + offset, [np.mean([r[key] for r in rows if r["technique"] == t]) for t in techniques],
                      0.4, label=label)
        costs.set_xticks(x, techniques, rotation=45, ha="right", fontsize=7)
        costs.set_ylabel("depth fetches per hard shadow ray")
        costs.grid(True, axis="y")
        costs.legend(fontsize=7)
        here = {r["technique"]: r["hard_wrong_own_hit"] for r in rows
                if r["heightmap"] == first and r["elevation"] == elevation}
        ranked = sorted(here, key=here.get)
        truth = masks["reference"]
        for i, label in enumerate(("reference", ranked[-1], ranked[0])):
            ax = fig.add_subplot(grid[1, 2 * i: 2 * i + 2])
            picture = np.repeat(masks[label][..., None].astype(np.float64), 3, axis=2)
            picture[masks[label] != truth] = (1.0, 0.0, 0.0)
            ax.imshow(picture, interpolation="nearest", aspect=truth.shape[1] / truth.shape[0])
            wrong = "" if label == "reference" else f", {here[label]:.1%} wrong"
            ax.set_title(f"{first}, light at {elevation:g}°: {label}{wrong}", fontsize=8)
            ax.axis("off")
        return save_png(fig, out / "shadows.png")
