"""The distance kind's GPU driver: the plain volume (``maptools/volume/distance.wgsl``), baked in slabs of slices."""

from __future__ import annotations

import numpy as np

from maptools.gpu import MapGpu, guard
from maptools.volume.cpu import check_subcells, check_volume
from maptools.volume.gpu import KERNEL, plain_slab, slab_slices, slabs, subcell_tops


@guard(KERNEL)
def distance(g: MapGpu, height: np.ndarray, *, slices: int = 16, height_scale: float = 0.05, subcells: int = 4):
    """GPU twin of volume.cpu.distance (distance.wgsl), baked in slabs of slices."""
    h, w = height.shape
    check_volume(w, h, slices)
    check_subcells(subcells, "distance")
    g.check_size(h, w)
    slab = slab_slices(g, w, h, slices, subcells)
    src = g.storage(height, "maptools distance src")
    tops = subcell_tops(g, src, w, h, height_scale, subcells, "distance")
    rows = g.storage(w * h * subcells * slab * 4, "maptools distance row pass")
    vol = g.storage(w * h * slab * 4, "maptools distance volume")
    out = np.empty((slices, h, w), np.float32)
    for first, count in slabs(slices, slab):
        enc = g.encoder("maptools distance slab")
        plain_slab(g, enc, tops, rows, vol, w, h, first, count, slices, height_scale, subcells)
        g.submit(enc)
        out[first:first + count] = g.read(vol, w * h * count).reshape(count, h, w)
    return out
