"""The filtering study's pictures: side-by-side crops (``crops_CASE.png``: the reference and filters, with their
difference images), ``pareto.png`` (error against GPU time, labels placed apart by ``place_labels``) and
``distributions.png`` (per-case PSNR differences against trilinear and against bilinear)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from wgpuviewer.core.errors import UserError
from wgpuviewer.core.io import write_bytes
from wgpuviewer.lab.harness.plots import pyplot, save_png

from .aggregate import _geomean, _mean, against, by_config, ranked
from .suites import BASELINE, BILINEAR, Config

#: The crops' panels: the reference, then these configurations (label, Config) where valid, then their
#: difference images.
CROP_PANELS = (
    ("bilinear", BILINEAR),
    ("trilinear", BASELINE),
    ("aniso 16", Config("aniso", "uv", (("max_anisotropy", 16),))),
    ("ewa analytic", Config("ewa", "analytic")),
    ("ewa displaced", Config("ewa", "displaced")),
    ("ewa_vis displ.", Config("ewa_vis", "displaced")),
    ("inherit displ.", Config("ewa_vis", "displaced", (("inherit", 1),))),
)
DIFF_GAIN = 4.0  # difference images: |filter - reference| x this
CROP = (40, 30)  # crop size, pixels (the window with the most occluded pixels)
ZOOM = 4


def _crop_window(mask: np.ndarray, size: tuple[int, int]) -> tuple[int, int]:
    """(y, x) of the size window with the most True pixels (the first one on ties)."""
    w, h = min(size[0], mask.shape[1]), min(size[1], mask.shape[0])
    s = np.pad(np.cumsum(np.cumsum(mask.astype(np.int64), 0), 1), ((1, 0), (1, 0)))
    counts = s[h:, w:] - s[:-h, w:] - s[h:, :-w] + s[:-h, :-w]
    y, x = np.unravel_index(int(np.argmax(counts)), counts.shape)
    return int(y), int(x)


def write_crops(out: Path, result, void: set[str]) -> str:
    import cv2

    ref = result.reference
    y, x = _crop_window(ref.occluded, CROP)
    h, w = min(CROP[1], ref.color.shape[0]), min(CROP[0], ref.color.shape[1])

    def crop(image):
        return np.clip(image[y:y + h, x:x + w], 0.0, 1.0)

    panels = [("reference", crop(ref.color))]
    diffs = [("occluded pixels", np.repeat(crop(ref.occluded.astype(np.float64))[..., None], 3, axis=2))]
    for name, config in CROP_PANELS:
        image = result.images.get(config)
        if image is None or config.label in void:
            continue
        panels.append((name, crop(image)))
        diffs.append((f"|{name} - ref| x{DIFF_GAIN:g}", np.clip(np.abs(crop(image) - crop(ref.color)) * DIFF_GAIN, 0, 1)))

    def strip(items):
        tiles = []
        for text, image in items:
            big = cv2.resize((image * 255).round().astype(np.uint8), (w * ZOOM, h * ZOOM),
                             interpolation=cv2.INTER_NEAREST)
            header = np.full((18, w * ZOOM, 3), 255, np.uint8)
            cv2.putText(header, text, (3, 13), cv2.FONT_HERSHEY_SIMPLEX, 0.42, (0, 0, 0), 1, cv2.LINE_AA)
            tiles.append(np.concatenate([header, big], 0))
            tiles.append(np.full((tiles[-1].shape[0], 4, 3), 255, np.uint8))
        return np.concatenate(tiles[:-1], 1)

    top, bottom = strip(panels), strip(diffs)
    width = max(top.shape[1], bottom.shape[1])
    parts = [np.pad(t, ((0, 0), (0, width - t.shape[1]), (0, 0)), constant_values=255) for t in (top, bottom)]
    picture = np.concatenate([parts[0], np.full((6, width, 3), 255, np.uint8), parts[1]], 0)
    name = f"crops_{result.case.name}.png"
    ok, encoded = cv2.imencode(".png", cv2.cvtColor(picture, cv2.COLOR_RGB2BGR))
    if not ok:
        raise UserError(f"{out / name}: could not encode the PNG")
    write_bytes(out / name, encoded.tobytes())
    return name


def place_labels(points: list[tuple[float, float]], widths: list[float], height: float, step: float,
                 marker: float = 0.0) -> list[tuple[float, float]]:
    """Offsets (display units) that keep every label's box (width x height, left edge at point + offset, centred
    vertically) clear of the boxes placed before it and of every point's marker (a square of side 2 ``marker``):
    right of the point first, then on its left, then further up or down in ``step``s."""
    placed = [(px - marker, py - marker, px + marker, py + marker) for px, py in points]
    offsets = []

    def clear(box):
        return all(box[2] <= b[0] or box[0] >= b[2] or box[3] <= b[1] or box[1] >= b[3] for b in placed)

    for (px, py), w in zip(points, widths):
        choice = None
        for k in range(0, 60):
            for dy in ((k * step,) if k == 0 else (k * step, -k * step)):
                for dx in (marker + 2.0, -marker - 2.0 - w):
                    box = (px + dx, py + dy - height / 2, px + dx + w, py + dy + height / 2)
                    if clear(box):
                        choice = (dx, dy, box)
                        break
                if choice:
                    break
            if choice:
                break
        if choice is None:  # more labels than room: the last resort overlaps
            choice = (marker + 2.0, 0.0, (px + marker + 2.0, py - height / 2, px + marker + 2.0 + w, py + height / 2))
        placed.append(choice[2])
        offsets.append(choice[:2])
    return offsets


def write_pareto(path: Path, rows: list[dict]) -> str | None:
    """Mean PSNR against the time ratio, one point per valid configuration, for relief with and without
    occlusion; None without matplotlib."""
    with pyplot() as plt:
        return None if plt is None else _draw_pareto(plt, path, ranked(rows))


def _draw_pareto(plt, path: Path, rows: list[dict]) -> str:
    kinds = [k for k in (True, False) if any(r["occluding"] == k for r in rows)]
    fig, axes = plt.subplots(1, len(kinds), figsize=(8 * len(kinds), 7), squeeze=False)
    fontsize = 6.5
    for ax, occluding in zip(axes[0], kinds):
        subset = [r for r in rows if r["occluding"] == occluding]
        points = []
        for name, group in by_config(subset).items():
            t, p = _geomean([r["time_ratio"] for r in group]), _mean([r["psnr"] for r in group])
            if math.isfinite(t) and math.isfinite(p):
                points.append((t, p, name))
        for t, p, name in points:
            colour = "tab:red" if "vis" in name else ("tab:blue" if "ewa" in name else "tab:grey")
            ax.scatter(t, p, color=colour, s=18, marker="s" if "pom32" in name else "o")
        front, best = [], -math.inf
        for t, p, _ in sorted(points):
            if p > best:
                best = p
                front.append((t, p))
        if front:
            ax.plot(*zip(*front), color="black", linewidth=0.8, linestyle="--", label="Pareto front")
            ax.legend(fontsize=7, loc="lower right")
        ax.set_xscale("log")
        ax.set_xlabel("GPU time / trilinear on the same tracer (geometric mean; software adapter)")
        ax.set_ylabel("PSNR against the box reference, dB (mean)")
        ax.set_title("relief with occlusion" if occluding else "flat relief")
        ax.grid(True, which="both")
        if points:
            ax.margins(x=0.25, y=0.12)
            fig.canvas.draw()
            xy = ax.transData.transform([(t, p) for t, p, _ in points])
            char_w = fontsize * 0.55 * fig.dpi / 72
            height = fontsize * 1.25 * fig.dpi / 72
            order = np.argsort(-xy[:, 1])
            offsets = place_labels([tuple(xy[i]) for i in order], [len(points[i][2]) * char_w for i in order],
                                   height, height * 0.6, marker=3.0 * fig.dpi / 72)
            for i, (dx, dy) in zip(order, offsets):
                t, p, name = points[i]
                pts = 72 / fig.dpi
                ax.annotate(name, (t, p), xytext=(dx * pts, dy * pts), textcoords="offset points", fontsize=fontsize,
                            va="center", arrowprops={"arrowstyle": "-", "color": "0.6", "linewidth": 0.5}
                            if dy else None)
    fig.tight_layout()
    return save_png(fig, path, dpi=120, tight=False)


def write_distributions(path: Path, rows: list[dict]) -> str | None:
    """Per configuration, the per-case PSNR differences against trilinear and against bilinear (same tracer) as
    box plots with every case's point over them, on the occluding cases; None without matplotlib."""
    with pyplot() as plt:
        return None if plt is None else _draw_distributions(plt, path, [r for r in ranked(rows) if r["occluding"]])


def _draw_distributions(plt, path: Path, rows: list[dict]) -> str | None:
    panels = [(f"PSNR - {BASELINE.label} (same tracer), dB", against(rows, BASELINE)),
              (f"PSNR - {BILINEAR.label} (same tracer), dB", against(rows, BILINEAR))]
    def order(name):  # by the mean gain over trilinear; trilinear itself (no difference) at the bottom
        m = _mean(panels[0][1].get(name, []))
        return m if math.isfinite(m) else -math.inf

    names = sorted({n for _, d in panels for n in d}, key=order)
    names = [n for n in names if any(d.get(n) for _, d in panels)]
    if not names:
        return None
    fig, axes = plt.subplots(1, 2, figsize=(14, 0.32 * len(names) + 1.8), sharey=True)
    rng = np.random.default_rng(0)
    for ax, (title, data) in zip(axes, panels):
        values = [data.get(n, []) for n in names]
        ax.boxplot([v if v else [math.nan] for v in values], orientation="horizontal", widths=0.6, showfliers=False)
        for i, v in enumerate(values, start=1):
            ax.scatter(v, i + rng.uniform(-0.18, 0.18, len(v)), s=6, alpha=0.5, color="tab:blue")
        ax.axvline(0.0, color="black", linewidth=0.8)
        ax.set_xlabel(title)
        ax.grid(True, axis="x")
    axes[0].set_yticks(range(1, len(names) + 1), names, fontsize=7)
    axes[0].set_title("relief with occlusion: per-case differences (box: quartiles; dots: cases)", fontsize=9,
                      loc="left")
    fig.tight_layout()
    return save_png(fig, path, dpi=110, tight=False)
