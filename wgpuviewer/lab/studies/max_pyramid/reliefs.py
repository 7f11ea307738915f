"""The study's reliefs and their classes: the paper expects the largest gain on reliefs with large flat areas
(bricks) and less on noisy ones.

- large flat areas: the builtin ``bricks``, scikit-image's bricks photograph ``brick`` and the generated ``plates``
  (square plates at seeded heights between narrow grooves);
- noisy: the builtin ``bumps``, scikit-image's ``grass`` and ``gravel`` photographs and ``dem``, a real digital
  elevation model: matplotlib's bundled sample ``jacksboro_fault_dem.npz`` (3 arc-second terrain, 344x403), its
  central square area-resized to the suite's size. A DEM does not tile, so its wrap is a seam (a cliff along two
  edges) that the repeat-addressed walk crosses like any relief.

The photographs need scikit-image and the DEM matplotlib (both in the ``bench`` extra); ``available`` drops the maps
whose package is missing. Generated maps are written to ``.npy`` so a scene could draw the same map.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

FLAT = "large flat areas"
NOISY = "noisy"
CLASSES = {"bricks": FLAT, "brick": FLAT, "plates": FLAT, "bumps": NOISY, "grass": NOISY, "gravel": NOISY,
           "dem": NOISY}
NAMES = tuple(CLASSES)
#: Plates: pitch and groove width in texels, the lowest plate top (the tallest is 1), the seed of their heights.
PLATE_PITCH = 32.0
PLATE_GROOVE = 4.0
PLATE_LOWEST = 0.55
PLATE_SEED = 7
DEM_SAMPLE = "jacksboro_fault_dem.npz"


def plates(size: int) -> np.ndarray:
    """float32 (size, size): square plates about PLATE_PITCH texels apart (the count rounded so the map tiles), flat
    tops at seeded heights in [PLATE_LOWEST, 1], PLATE_GROOVE-wide grooves down to 0 between them."""
    n = max(1, round(size / PLATE_PITCH))
    pitch = size / n
    y, x = np.mgrid[0:size, 0:size] + 0.5
    i, j = np.floor(x / pitch).astype(int), np.floor(y / pitch).astype(int)
    tops = PLATE_LOWEST + (1.0 - PLATE_LOWEST) * np.random.default_rng(PLATE_SEED).random((n, n))
    tops.flat[0] = 1.0  # the global maximum is a whole plate (the paper's early exit has somewhere to fire)
    fx, fy = x - i * pitch, y - j * pitch
    half = PLATE_GROOVE / 2
    inside = (fx >= half) & (fx <= pitch - half) & (fy >= half) & (fy <= pitch - half)
    return np.where(inside, tops[j, i], 0.0).astype(np.float32)


def dem(size: int) -> np.ndarray:
    """float32 (size, size) in [0, 1]: the DEM sample's central square, area-resized to ``size``, normalised."""
    import cv2
    from matplotlib import cbook

    elevation = np.asarray(cbook.get_sample_data(DEM_SAMPLE)["elevation"], np.float64)
    side = min(elevation.shape)
    r0, c0 = (elevation.shape[0] - side) // 2, (elevation.shape[1] - side) // 2
    square = cv2.resize(elevation[r0:r0 + side, c0:c0 + side], (size, size), interpolation=cv2.INTER_AREA)
    return ((square - square.min()) / (square.max() - square.min())).astype(np.float32)


GENERATED = {"plates": (plates, f"generated plates, pitch {PLATE_PITCH:g}, grooves {PLATE_GROOVE:g} texels"),
             "dem": (dem, f"matplotlib sample {DEM_SAMPLE} (USGS terrain), central square area-resized")}


def available(names) -> tuple[str, ...]:
    """``names`` without the maps whose optional package (scikit-image, matplotlib) is not installed."""
    from wgpuviewer.lab.bench.run import REAL_MAPS, skimage_available

    missing = set(REAL_MAPS) if not skimage_available() else set()
    try:
        import matplotlib  # noqa: F401
    except ImportError:
        missing.add("dem")
    return tuple(n for n in names if n not in missing)


def load(name: str, size: int, workdir: Path):
    """The height map ``name`` at ``size``² (a ``bench.view.HeightMap``): builtins and generated maps made at that
    size, the photographs area-downscaled to it."""
    from wgpuviewer.lab.bench.view import HeightMap, load_heightmap

    if name not in GENERATED:
        return load_heightmap(name, size, workdir, real_size=size)
    make, source = GENERATED[name]
    height = make(size)
    path = Path(workdir) / f"max_pyramid_{name}_{size}.npy"
    np.save(path, height)
    texture = '"' + str(path).replace("\\", "\\\\").replace('"', '\\"') + '"'
    return HeightMap(name, height, texture, f"{source}, {size}x{size}")
