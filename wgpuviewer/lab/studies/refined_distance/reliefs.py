"""The paper's relief: flat tops perforated by deep, narrow pits and slots, where the Euclidean distance stays small
along every ray that passes over an opening while almost every ray that reaches a point there arrives from above it
(the case the visibility condition of Romanyuk et al. 2017 is made for). Generated in code, periodic, as benchmark
height maps (``wgpuviewer.lab.bench.view.HeightMap``) written to ``.npy`` so the renderer draws the same map.

- ``plate``: a perforated plate: round holes 5 texels across, 12 texels apart, from the top (height 1) to the
  bottom (height 0), a hexagonal pattern;
- ``grille``: a grille of slots 1, 2 and 3 texels wide and 16 texels long, full depth, in a flat top.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

#: Hole spacing and diameter of the plate, texels.
PLATE_PITCH = 12.0
PLATE_DIAMETER = 5.0
#: Slot widths of the grille (texels), its slot length and the gap between slots (texels).
SLOT_WIDTHS = (1, 2, 3)
SLOT_LENGTH = 16
SLOT_GAP = 5


def _periodic_count(size: int, pitch: float) -> int:
    return max(1, round(size / pitch))


def plate(size: int, diameter: float = PLATE_DIAMETER, pitch: float = PLATE_PITCH) -> np.ndarray:
    """float32 (size, size): 1 on the top, 0 in round holes of ``diameter`` texels on a hexagonal grid of about
    ``pitch`` texels (the count per side rounded so the map tiles)."""
    n = _periodic_count(size, pitch)
    rows = max(2, 2 * round(size / (pitch * np.sqrt(3) / 2) / 2))  # even: the shifted rows tile
    pitch_x, pitch_y = size / n, size / rows
    y, x = np.mgrid[0:size, 0:size] + 0.5
    row = np.floor(y / pitch_y)
    shift = (row % 2) * pitch_x / 2
    cx = (np.floor((x - shift) / pitch_x) + 0.5) * pitch_x + shift
    cy = (row + 0.5) * pitch_y
    r = np.hypot(x - cx, y - cy)
    return np.where(r <= diameter / 2, 0.0, 1.0).astype(np.float32)


def grille(size: int) -> np.ndarray:
    """float32 (size, size): 1 on the top, 0 in vertical slots SLOT_WIDTHS texels wide (cycling), SLOT_LENGTH
    long, at least SLOT_GAP apart both ways, every other column shifted by half a pitch (the map tiles)."""
    out = np.ones((size, size), np.float32)
    per_column = max(1, size // (SLOT_LENGTH + SLOT_GAP))  # slots per column: the gaps at least SLOT_GAP
    pitch_y = size / per_column
    x = 0
    column = 0
    while x < size:
        w = SLOT_WIDTHS[column % len(SLOT_WIDTHS)]
        if x + w + SLOT_GAP > size:
            break
        offset = column * pitch_y / 2  # staggered columns
        for r in range(per_column):
            y0 = round(r * pitch_y + offset)
            out[np.arange(y0, y0 + SLOT_LENGTH) % size, x:x + w] = 0.0  # wrapped: the map tiles
        x += w + SLOT_GAP
        column += 1
    return out


GENERATORS = {"plate": plate, "grille": grille}
NAMES = tuple(GENERATORS)


def load(name: str, size: int, workdir: Path):
    """The generated height map ``name`` at ``size``² (a ``bench.view.HeightMap``), written to ``workdir`` as .npy
    for the renderer's scene."""
    from wgpuviewer.lab.bench.view import HeightMap

    height = GENERATORS[name](size)
    path = Path(workdir) / f"generated_{name}_{size}.npy"
    if not path.exists():
        np.save(path, height)
    texture = '"' + str(path).replace("\\", "\\\\").replace('"', '\\"') + '"'
    return HeightMap(name, height, texture, f"generated {name} {size}x{size} (studies.refined_distance.reliefs)")
