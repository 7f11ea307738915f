"""The plain volume's GPU bake (``distance.wgsl``), which both distance kinds run: the ``distance`` kind's map, and
the ``distance_refined`` kind's last volume and floor.

The volumes are baked in slabs of consecutive slices (each slab's buffers within the adapter's storage limit):
the sub-cell tops, the window tops and the column lists are made once, the passes run slab by slab, and each
slab is read back into the whole volume. A slab's kernels offset their slice index by ``first_slice``.
"""

from __future__ import annotations

from maptools.gpu import FIX, MapGpu, map_kernel

from .cpu import BOX_GROW, STORE_MARGIN, SUBCELLS

KERNEL = map_kernel(__file__, "distance.wgsl", [
    ("width", "u32"), ("height", "u32"),
    ("first_slice", "u32"), ("slices", "u32"),  # the slab baked: slices [first_slice, first_slice + slices)
    ("subcells", "u32"),  # K
    ("sw", "f32"),  # S * W: metric length of the whole depth range t in [0, 1]
    ("sy", "f32"),  # W / H: metric height of one texel row
    ("dz", "f32"),  # metric thickness of one slice
    ("grow", "f32"),  # every voxel box is grown by this on each side (volume.cpu.BOX_GROW)
    ("margin", "f32")])  # subtracted from every stored distance


def bake_buffers(w: int, h: int, subcells: int, lanes: int = 0) -> tuple[int, int]:
    """(bytes of the buffers made once, bytes per slice of a slab) of a w x h volume bake with K = ``subcells``:
    the sub-cell tops (K^2 floats a texel) once; per slice the row pass (K floats a texel), the volume, and for
    the refined bake ``lanes`` band volumes. Each is one storage buffer, so each must fit the binding limit."""
    once = w * h * subcells * subcells * 4
    per_slice = w * h * 4 * max(subcells, lanes, 1)
    return once, per_slice


def fitting_subcells(w: int, h: int, max_buffer: int, lanes: int = 0, most: int = 4) -> int | None:
    """The largest sub-cell count (of ``cpu.SUBCELLS``, at most ``most``) whose bake of a w x h volume fits
    storage buffers of ``max_buffer`` bytes with slabs of one slice; None when none does."""
    for k in sorted((k for k in SUBCELLS if k <= most), reverse=True):
        if max(bake_buffers(w, h, k, lanes)) <= max_buffer:
            return k
    return None


def slab_slices(g: MapGpu, w: int, h: int, slices: int, subcells: int, lanes: int = 0) -> int:
    """Slices per slab: as many as the storage limit allows (all of them when the volume fits whole)."""
    once, per_slice = bake_buffers(w, h, subcells, lanes)
    what = f"a {w}x{h} volume with {subcells}x{subcells} sub-cells"
    fix = f"use fewer --subcells, downscale the height map or {FIX}"
    g.compute.check_buffer(once, f"{what} (its sub-cell tops)", fix)
    g.compute.check_buffer(per_slice, f"{what} (one slice)", fix)
    return max(1, min(slices, g.compute.max_buffer // per_slice))


def slabs(slices: int, slab: int) -> list[tuple[int, int]]:
    """(first slice, slice count) of each slab."""
    return [(k0, min(slab, slices - k0)) for k0 in range(0, slices, slab)]


def distance_params(w: int, h: int, first: int, count: int, height_scale: float, subcells: int, slices: int) -> dict:
    return {"width": w, "height": h, "first_slice": first, "slices": count, "subcells": subcells,
            "sw": height_scale * w, "sy": w / h, "dz": height_scale * w / slices, "grow": BOX_GROW,
            "margin": STORE_MARGIN}


def subcell_tops(g: MapGpu, src, w: int, h: int, height_scale: float, subcells: int, label: str):
    """The sub-cell tops buffer (distance.wgsl ``tops``), computed and submitted."""
    k = subcells
    tops = g.storage(w * h * k * k * 4, f"maptools {label} sub-cell tops")
    params = g.uniform(KERNEL, distance_params(w, h, 0, 1, height_scale, k, 1))
    enc = g.encoder(f"maptools {label} tops")
    g.dispatch(enc, KERNEL, "tops", {0: params, 1: src, 2: tops}, w * k, h * k, 1)
    g.submit(enc)
    return tops


def plain_slab(g: MapGpu, enc, tops, rows, out, w: int, h: int, first: int, count: int, slices: int,
                height_scale: float, subcells: int) -> None:
    """Encode pass_x + pass_y of distance.wgsl for slices [first, first + count) into ``out`` (the slab's
    stored plain values, indexed (slice - first, row, column))."""
    params = g.uniform(KERNEL, distance_params(w, h, first, count, height_scale, subcells, slices))
    g.dispatch(enc, KERNEL, "pass_x", {0: params, 1: tops, 2: rows}, w, h * subcells, count)
    g.dispatch(enc, KERNEL, "pass_y", {0: params, 1: rows, 2: out}, w, h, count)
