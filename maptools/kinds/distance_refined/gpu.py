"""The distance_refined kind's GPU driver: per slab the plain volume (``maptools/volume/distance.wgsl``), then
``distance_refined.wgsl`` per azimuth sector and group of up to 4 bands."""

from __future__ import annotations

import numpy as np

from maptools.gpu import FIX, MapGpu, guard, map_kernel
from maptools.volume import cpu as dist
from maptools.volume.gpu import KERNEL as PLAIN_KERNEL
from maptools.volume.gpu import plain_slab, slab_slices, slabs, subcell_tops

from .bins import BANDS_PER_PASS, HORIZON_STEP, bins, entries
from .cpu import check, check_visibility
from .visibility import COT_SLACK, horizon_rings, ring_count

KERNEL = map_kernel(__file__, "distance_refined.wgsl", [
    ("width", "u32"), ("height", "u32"), ("first_slice", "u32"), ("slices", "u32"), ("subcells", "u32"),
    ("count", "u32"),  # columns in the list
    ("levels", "u32"),  # window levels (window_tops)
    ("bands", "u32"),  # polar bands written (1 to 4), one per vec4 lane of:
    ("tan_lo", "vec4f"),  # tan of the band's least polar angle
    ("cot_hi", "vec4f"),  # cot of its largest polar angle
    ("inv_sin_hi", "vec4f"),  # 1 / sin of its largest polar angle
    ("cap", "vec4f"),  # reach / sin of its largest polar angle
    ("dz", "f32"), ("grow", "f32"), ("margin", "f32"), ("sw", "f32"),  # as distance.wgsl's
    ("visibility", "u32"),  # 1: cut each voxel's polar range by reach_cot (the paper's visibility condition)
    ("rings", "u32"),  # horizon: backward distances tested, ring n at (n + 1) * horizon_step
    ("horizon_step", "f32"), ("reach", "f32"),
    ("cot_slack", "f32")])  # cot of the bins' angle slack (visibility.COT_SLACK)


def _visibility_buffers(g: MapGpu, w: int, h: int, slab: int, sectors: int, max_angle: float, reach: float):
    """(inner tops, the slab's cut, per sector its ring offsets and ring ends) of the visibility condition."""
    inner = g.storage(w * h * 4, "maptools distance_refined inner tops")
    cut = g.storage(w * h * slab * 4, "maptools distance_refined visibility cut")
    rings, ring_ends = [], []
    for b in bins(sectors, 1, max_angle):
        ring = horizon_rings(b, w / h, reach)
        offsets = np.concatenate([np.stack([np.mod(ox, w), np.mod(oy, h)], axis=1) for ox, oy in ring])
        # a storage buffer is never empty: one unread entry where no ring holds a cell
        rings.append(g.storage(offsets.astype(np.uint32) if len(offsets) else np.zeros((1, 2), np.uint32),
                               "maptools distance_refined rings"))
        ends = np.cumsum([len(ox) for ox, _ in ring]).astype(np.uint32)
        ring_ends.append(g.storage(ends, "maptools distance_refined ring ends"))
    return inner, cut, rings, ring_ends


def _pass_params(g: MapGpu, w: int, h: int, first: int, count: int, group: list, columns: int, levels: int,
                 subcells: int, slices: int, height_scale: float, reach: float, visible: bool):
    """The Params uniform of one pass: the bands of ``group``, one per vec4 lane (unused lanes 0)."""
    lane = [0.0] * (4 - len(group))
    return g.uniform(KERNEL, {
        "width": w, "height": h, "first_slice": first, "slices": count, "subcells": subcells,
        "count": columns, "levels": levels, "bands": len(group),
        "tan_lo": [d.tan_lo for d in group] + lane, "cot_hi": [d.cot_hi for d in group] + lane,
        "inv_sin_hi": [1.0 / d.sin_hi for d in group] + lane, "cap": [reach / d.sin_hi for d in group] + lane,
        "dz": height_scale * w / slices, "grow": dist.BOX_GROW, "margin": dist.STORE_MARGIN,
        "sw": height_scale * w, "visibility": int(visible), "rings": ring_count(reach),
        "horizon_step": HORIZON_STEP, "reach": reach, "cot_slack": COT_SLACK})


@guard(PLAIN_KERNEL, KERNEL)
def distance_refined(g: MapGpu, height: np.ndarray, *, slices: int = 16, height_scale: float = 0.05,
                     subcells: int = 4, max_angle: float = 85.0, sectors: int = 4, bands: int = 8,
                     reach: float = 16.0, visibility: str = "off", progress: bool = True):
    """GPU twin of cpu.distance_refined, baked in slabs of slices: per slab the plain volume (distance.wgsl),
    then one dispatch of distance_refined.wgsl per azimuth sector and group of up to 4 bands, each read back and
    rounded down to float16. With the visibility condition, each sector's cut (``horizon``) first, per slab."""
    from tqdm import tqdm

    h, w = height.shape
    check(w, h, slices, sectors, bands)
    dist.check_subcells(subcells, "distance_refined")
    check_visibility(visibility)
    g.check_size(h, w)
    visible = visibility == "on"
    lanes = min(bands, BANDS_PER_PASS)
    slab = slab_slices(g, w, h, slices, subcells, lanes)
    directions = bins(sectors, bands, max_angle)
    lists = [entries(directions[s], subcells, w / h, reach) for s in range(sectors)]  # band independent
    levels = max(e.levels for e in lists)
    g.compute.check_buffer(levels * w * h * 4, f"the window tops of a {w}x{h} height map",
                           f"downscale the height map or {FIX}")
    src = g.storage(height, "maptools distance_refined src")
    tops = subcell_tops(g, src, w, h, height_scale, subcells, "distance_refined")
    rows = g.storage(w * h * subcells * slab * 4, "maptools distance_refined row pass")
    plain = g.storage(w * h * slab * 4, "maptools distance_refined plain slab")
    vol = g.storage(lanes * w * h * slab * 4, "maptools distance_refined band volumes")
    windows = g.storage(levels * w * h * 4, "maptools distance_refined window tops")
    columns = [g.storage(e.packed(w, h, subcells), "maptools distance_refined columns") for e in lists]
    inner = cut = rings = ring_ends = None
    if visible:
        inner, cut, rings, ring_ends = _visibility_buffers(g, w, h, slab, sectors, max_angle, reach)
    out = np.empty((len(directions) + 1, slices, h, w), np.float16)
    groups = [(s, b0) for s in range(sectors) for b0 in range(0, bands, BANDS_PER_PASS)]
    passes = [(slab_, group) for slab_ in slabs(slices, slab) for group in groups]
    windows_done = False
    for (first, count), (sector, b0) in tqdm(passes, desc="distance_refined (gpu)", unit="pass",
                                              disable=None if progress else True, leave=False):
        n = w * h * count
        group = [directions[b * sectors + sector] for b in range(b0, min(b0 + BANDS_PER_PASS, bands))]
        p = _pass_params(g, w, h, first, count, group, len(lists[sector].rho), levels, subcells, slices,
                         height_scale, reach, visible)
        enc = g.encoder("maptools distance_refined pass")
        if not windows_done:
            g.dispatch(enc, KERNEL, "window_tops", {0: p, 1: src, 2: windows}, w, h, levels)
            if visible:
                g.dispatch(enc, KERNEL, "inner_tops", {0: p, 1: src, 2: inner}, w, h)
            windows_done = True
        if (sector, b0) == groups[0]:  # the slab's plain values, which every pass of the slab floors at
            plain_slab(g, enc, tops, rows, plain, w, h, first, count, slices, height_scale, subcells)
        if visible and b0 == 0:  # the sector's cut for the slab, which its band groups share
            g.dispatch(enc, KERNEL, "horizon", {0: p, 1: inner, 2: cut, 7: rings[sector], 8: ring_ends[sector]}, w, h)
        g.dispatch(enc, KERNEL, "main",
                   {0: p, 1: plain, 2: vol, 3: tops, 4: windows, 5: columns[sector], 6: cut if visible else plain},
                   w, h, count)
        g.submit(enc)
        if (sector, b0) == groups[0]:
            stored = dist.round_down(g.read(plain, n).astype(np.float64), np.float16)
            out[-1, first:first + count] = stored.reshape(count, h, w)
        result = dist.round_down(g.read(vol, len(group) * n).astype(np.float64), np.float16)
        for i, b in enumerate(range(b0, b0 + len(group))):
            out[b * sectors + sector, first:first + count] = result[i * n:(i + 1) * n].reshape(count, h, w)
    return out
