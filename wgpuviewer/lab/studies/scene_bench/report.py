"""The scene benchmark's report: per scene the configurations' means over the views, the goal (auto at a 0.5-pixel
budget against POM 24), the Pareto plot of FLIP against SIMD-tile fetches (pareto.png) and crops of the worst
pixels (worst_pixels.png); ``aggregate`` and ``goal_lines`` also make docs/benchmarks.md's block (``docs``)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from wgpuviewer.lab.harness.header import Header
from wgpuviewer.lab.harness.plots import MISSING, pyplot, save_png

from .configs import EXACT, GOAL_FETCH_RATIO, config_key, goal_keys
from .scenes import FAR, GRAZING_DEGREES, NEAR

CROP = 48  # pixels per side of a worst-pixels crop
CROP_ZOOM = 4
WINDOW = 9  # pixels per side of the box the worst spot's FLIP is averaged over
MEANS = ("fetches_mean", "fetches_simd", "px_err_p50", "px_err_p95", "px_err_over_half", "flip_mean", "psnr_db",
         "silhouette", "capped")


def label(key: tuple[str, str]) -> str:
    return key[0] if key[1] == "-" else f"{key[0]} {key[1]}"


def shown_configs(keys: list[tuple[str, str]]) -> tuple:
    """The configurations whose pictures the crops show, the one whose worst pixels they seek first: the goal's two
    where both are drawn, else the last auto (or the last configuration) and POM 24 where drawn."""
    goal = goal_keys()
    if goal is not None and all(k in keys for k in goal):
        return goal
    autos = [k for k in keys if k[0] == "auto"]
    first = autos[-1] if autos else keys[-1]
    return (first, *(k for k in keys if k == ("pom", "layers=24") and k != first))


def aggregate(rows: list[dict]) -> dict:
    """scene -> (technique, params) -> the means over the scene's views of MEANS, and ``ratio_to_basic`` as their
    geometric mean, in the rows' order."""
    out: dict = {}
    for row in rows:
        out.setdefault(row["scene"], {}).setdefault((row["technique"], row["params"]), []).append(row)
    result = {}
    for scene, by_config in out.items():
        result[scene] = {}
        for key, group in by_config.items():
            means = {m: float(np.mean([r[m] for r in group])) for m in MEANS}
            means["ratio_to_basic"] = float(np.exp(np.mean([math.log(r["ratio_to_basic"]) for r in group])))
            means["views"] = len(group)
            result[scene][key] = means
    return result


def goal_lines(table: dict) -> list[str]:
    """The goal's table: per scene POM 24's and auto (0.5 px)'s SIMD-tile fetches and FLIP, met or not."""
    goal = goal_keys()
    if goal is None:
        return ["auto's `max_error_px` is not in this checkout: the goal's configuration was not measured."]
    auto, pom = goal
    lines = [f"| scene | POM 24: SIMD-tile fetches | FLIP | {label(auto)}: SIMD-tile fetches | FLIP | fetches "
             f"/ POM 24's | FLIP / POM 24's | goal (FLIP ≤ POM 24's, fetches ≤ {GOAL_FETCH_RATIO:g}x) |",
             "|---|---|---|---|---|---|---|---|"]
    for scene, by_config in table.items():
        if auto not in by_config or pom not in by_config:
            continue
        a, p = by_config[auto], by_config[pom]
        ratio = a["fetches_simd"] / p["fetches_simd"]
        flip_ok, fetch_ok = a["flip_mean"] <= p["flip_mean"], ratio <= GOAL_FETCH_RATIO
        verdict = "met" if flip_ok and fetch_ok else "not met: " + " and ".join(
            what for what, ok in (("FLIP above POM 24's", flip_ok), (f"fetches above {GOAL_FETCH_RATIO:g}x", fetch_ok))
            if not ok)
        lines.append(f"| {scene} | {p['fetches_simd']:.1f} | {p['flip_mean']:.4f} | {a['fetches_simd']:.1f} | "
                     f"{a['flip_mean']:.4f} | {ratio:.2f}x | {a['flip_mean'] / p['flip_mean']:.3f}x | {verdict} |")
    return lines if len(lines) > 2 else [f"This run drew neither `{label(auto)}` nor `{label(pom)}` on a scene "
                                         "(the full suite draws both)."]


def scene_table(by_config: dict) -> list[str]:
    lines = ["| configuration | time / basic | fetches | SIMD-tile | px p50 | px p95 | > 0.5 px | FLIP | PSNR dB | "
             "silhouette |", "|---|---|---|---|---|---|---|---|---|---|"]
    for key, m in by_config.items():
        lines.append(f"| `{label(key)}` | {m['ratio_to_basic']:.2f} | {m['fetches_mean']:.1f} | "
                     f"{m['fetches_simd']:.1f} | {m['px_err_p50']:.3f} | {m['px_err_p95']:.2f} | "
                     f"{m['px_err_over_half']:.1%} | {m['flip_mean']:.4f} | {m['psnr_db']:.1f} | "
                     f"{m['silhouette']:.2%} |")
    return lines


def write_report(out: Path, header: Header, rows: list[dict], crops: list, suite, size) -> str:
    """report.md's text; writes pareto.png and worst_pixels.png beside it."""
    table = aggregate(rows)
    exact = label(config_key(*EXACT))
    lines = header.lines() + [
        f"- frame: {size[0]}x{size[1]}; views {', '.join(suite.views)} (near: {NEAR:g}x the scene camera's distance "
        f"to its target, far: {FAR:g}x, grazing: {GRAZING_DEGREES:g}° above the target's foot on y = 0); "
        f"{suite.frames} timed frames per configuration and view",
        f"- reference: the exact tracer `{exact}`, rendered at the same pixels",
        "",
        "Per scene, means over its views (time / basic: their geometric mean). `px`: hit error in screen pixels "
        "against the exact tracer's hit (the uv difference through the inverse of the pixel's screen-to-uv "
        "Jacobian), over the pixels both cover; FLIP (NVIDIA FLIP, LDR, 67 pixels per degree) and PSNR: colour "
        "against the exact render over the pixels either covers; silhouette: the share of those only one covers. "
        "Fetches: depth fetches per pixel, mean and SIMD-tile (per 8x4 tile, the slowest lane's).",
        "", "## Goal: auto at 0.5 pixel against POM 24", "", *goal_lines(table), "",
    ]
    for scene, by_config in table.items():
        lines += [f"## {scene}", "", *scene_table(by_config), ""]
    pareto, worst = _pareto(out, table), _worst(out, crops)
    lines += ["## FLIP against SIMD-tile fetches", "",
              f"![FLIP against SIMD-tile fetches]({pareto})" if pareto else MISSING, "",
              "## Worst pixels", ""]
    if worst:
        lines += ["Per scene, the view where the first configuration shown has the highest mean FLIP, cropped "
                  f"({CROP}x{CROP} pixels, {CROP_ZOOM}x) around its worst {WINDOW}x{WINDOW} spot: the exact render, "
                  "the configurations, the first one's FLIP map.", "", f"![worst pixels]({worst})", ""]
    else:
        lines += [MISSING, ""]
    return "\n".join(lines)


def _pareto(out: Path, table: dict) -> str | None:
    with pyplot() as plt:
        if plt is None:
            return None
        fig, axes = plt.subplots(1, len(table), figsize=(4.6 * len(table), 4.2), squeeze=False)
        for ax, (scene, by_config) in zip(axes[0], table.items()):
            points = [(m["fetches_simd"], m["flip_mean"], key) for key, m in by_config.items() if key[0] != "basic"]
            for x, y, key in points:
                ax.scatter(x, y, s=18, color="C1" if key[0] == "auto" else "C0")
                ax.annotate(label(key).replace("max_error", "e"), (x, y), fontsize=6, xytext=(3, 2),
                            textcoords="offset points")
            front, best = [], float("inf")
            for x, y, _ in sorted(points):
                if y < best:
                    front.append((x, y))
                    best = y
            ax.plot(*zip(*front), color="0.6", lw=0.8, ls="--", zorder=0)
            ax.set_title(scene, fontsize=9)
            ax.set_xlabel("SIMD-tile fetches per pixel")
            ax.set_ylabel("FLIP against the exact render")
            ax.grid(True)
        return save_png(fig, out / "pareto.png")


def worst_spot(flip: np.ndarray) -> tuple[int, int]:
    """(row, column) of the centre of the WINDOW-square box with the highest mean FLIP."""
    import cv2

    smooth = cv2.blur(flip.astype(np.float32), (WINDOW, WINDOW))
    return np.unravel_index(int(np.argmax(smooth)), smooth.shape)


def _worst(out: Path, crops: list) -> str | None:
    if not crops:
        return None
    with pyplot() as plt:
        if plt is None:
            return None
        first = next(iter(crops[0].shown))
        worst = {}
        for crop in crops:
            if crop.scene not in worst or crop.shown[first][1].mean() > worst[crop.scene].shown[first][1].mean():
                worst[crop.scene] = crop
        columns = 2 + len(crops[0].shown)
        fig, axes = plt.subplots(len(worst), columns, figsize=(2.4 * columns, 2.5 * len(worst)), squeeze=False)
        for ax_row, crop in zip(axes, worst.values()):
            y, x = worst_spot(crop.shown[first][1])
            h, w = crop.exact.shape[:2]
            side = min(CROP, h, w)
            top, left = int(np.clip(y - side // 2, 0, h - side)), int(np.clip(x - side // 2, 0, w - side))
            window = (slice(top, top + side), slice(left, left + side))
            pictures = [("exact", crop.exact[window])] + [(label(k), c[window]) for k, (c, _) in crop.shown.items()]
            for ax, (title, picture) in zip(ax_row, pictures):
                ax.imshow(np.kron(picture, np.ones((CROP_ZOOM, CROP_ZOOM, 1), np.uint8)), interpolation="nearest")
                ax.set_title(f"{crop.scene} {crop.view}:\n{title}", fontsize=6)
            ax_row[-1].imshow(crop.shown[first][1][window], cmap="magma", vmin=0.0, vmax=1.0, interpolation="nearest")
            ax_row[-1].set_title(f"FLIP of\n{label(first)}", fontsize=6)
            for ax in ax_row:
                ax.axis("off")
        return save_png(fig, out / "worst_pixels.png", dpi=90)
