"""The renderer's side of the distance volumes, shared by the distance kinds' slots: the settings a height map's volume
gets on this adapter (``volume_plan``: the default depth slices and sub-cells where they fit, else the most that do,
said in one warning line when the map is built; refused only below the fewest slices) and the upload as an
r16float 3D texture (``uploaded_volume``).

May import: ``wgpuviewer.core``, numpy, wgpu and maptools' shared modules.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import wgpu

from wgpuviewer.core.compute import compute_for
from wgpuviewer.core.errors import UserError
from wgpuviewer.core.gpu import Gpu, allocating, format_bytes
from wgpuviewer.core.slots import fits_texels, size_of

from . import cpu as volume_cpu
from . import gpu as volume_gpu

log = logging.getLogger("wgpuviewer.relief.maps")


#: Depth slices and sub-cells per cell side of the distance volumes where they fit (maptools' defaults).
DISTANCE_SLICES = 16
DISTANCE_SUBCELLS = 4
#: Fewest depth slices a volume is reduced to; a height map that does not fit even so is refused. Fewer slices stay
#: exact but cost fetches (docs/maps.md, "Large height maps"): a slice spans S*W/Dz texels of depth.
MIN_SLICES = 4
#: A refined map of at most this many slices saves no fetches over the plain map at 16 (measured at 1K and 2K:
#: docs/maps.md, "Large height maps"): where that is all that fits, the one line says so.
REFINED_PAYS_SLICES = DISTANCE_SLICES // 2


@dataclass(frozen=True)
class VolumePlan:
    """How a distance slot's volume is built from a W x H height map on this adapter: its depth slices and
    sub-cells, the largest (up to the defaults) that fit the adapter's and maptools' limits, and what made them
    smaller (``reduced``: one clause per reduction; empty: the defaults)."""

    kind: str
    width: int
    height: int
    slices: int
    subcells: int
    reduced: tuple[str, ...] = ()
    #: A better choice where the user is, or "" (a refined map with few slices: the plain one at more slices).
    advice: str = ""
    volumes: int = 1  # volumes stacked along the depth (a binned kind's bins and its plain volume)

    @property
    def nbytes(self) -> int:
        """Bytes of the texture: float16 volumes (``uploaded_volume``)."""
        return self.width * self.height * self.slices * self.volumes * 2

    def note(self, label: str) -> str:
        """The one line saying what was chosen and why (for a reduced plan)."""
        return (f"{label}: a {self.width}x{self.height} height map gets {'; '.join(self.reduced)}; "
                f"{format_bytes(self.nbytes)}; the tracer stays exact, at more fetches per ray"
                f"{'; ' + self.advice if self.advice else ''} (docs/maps.md)")


@dataclass(frozen=True)
class Binned:
    """What a direction-binned volume kind adds to its plan: the volumes it stacks (its bins and the plain one),
    maptools' limit on its values (float16) and the band volumes its bake holds per pass (``lanes``)."""

    volumes: int
    max_values: int
    lanes: int


def volume_plan(gpu: Gpu, kind: str, w: int, h: int, binned: Binned | None = None) -> VolumePlan:
    """The settings a w x h height map's ``kind`` volume (the plain one, or ``binned``'s) is built with here: the
    defaults, else the most slices (down to MIN_SLICES) and sub-cells within the adapter's 3D texture limit,
    maptools' volume limits and the adapter's storage buffers (the bake binds the sub-cell tops whole); a
    UserError naming what the scene can change when even the fewest do not fit."""
    refined = binned is not None
    volumes = binned.volumes if refined else 1
    side = gpu.device.limits["max-texture-dimension-3d"]
    if max(w, h) > side:
        raise UserError(f"{kind}: a volume of {w}x{h} texels per slice exceeds this adapter's 3D limit of {side} "
                        f"texels per side; use a height map of at most {side} texels per side")

    def layers(n: int) -> str:
        return f"{volumes} x {n} slices stack {volumes * n} layers, more than this adapter's 3D limit of {side} texels"

    def values(limit: int, unit: str, per_volume: int) -> Callable[[int], str]:
        held = f"{per_volume} volumes of {w}x{h}x{{}} hold" if per_volume > 1 else f"a {w}x{h}x{{}} volume holds"
        return lambda n: (f"{held.format(n)} {per_volume * n * w * h} values, more than maptools' limit of {limit} "
                          f"({unit})")

    # (most slices within the limit, what n slices exceed, the fix when MIN_SLICES exceed it)
    limits = [(side // volumes, layers, "use the technique distance")]
    if refined:
        limits.append((binned.max_values // (w * h * volumes),
                       values(binned.max_values, "float16", volumes),
                       fits_texels(w, h, binned.max_values // (volumes * MIN_SLICES))
                       + ", or the technique distance"))
    limits.append((volume_cpu.MAX_VOXELS // (w * h), values(volume_cpu.MAX_VOXELS, "float32", 1),
                   fits_texels(w, h, volume_cpu.MAX_VOXELS // MIN_SLICES)))
    for most, exceeded, fix in limits:
        if most < MIN_SLICES:
            raise UserError(f"{kind}: even at {MIN_SLICES} depth slices (the fewest it is built with) "
                            f"{exceeded(MIN_SLICES)}; {fix}")
    slices = min(DISTANCE_SLICES, *(most for most, _, _ in limits))
    reduced = [f"{slices} depth slices instead of {DISTANCE_SLICES} ({exceeded(DISTANCE_SLICES)})"
               for most, exceeded, _ in limits if most == slices < DISTANCE_SLICES][:1]
    max_buffer = compute_for(gpu).max_buffer
    lanes = binned.lanes if refined else 0
    subcells = volume_gpu.fitting_subcells(w, h, max_buffer, lanes, most=DISTANCE_SUBCELLS)
    if subcells is None:
        raise UserError(f"{kind}: baking a {w}x{h} volume needs storage buffers of "
                        f"{format_bytes(max(volume_gpu.bake_buffers(w, h, 1, lanes)))}, more than the "
                        f"{format_bytes(max_buffer)} this adapter binds; use a smaller height map")
    if subcells < DISTANCE_SUBCELLS:
        need = max(volume_gpu.bake_buffers(w, h, DISTANCE_SUBCELLS, lanes))
        reduced.append(f"{subcells}x{subcells} sub-cells per cell instead of {DISTANCE_SUBCELLS}x"
                       f"{DISTANCE_SUBCELLS} (whose bake needs a {format_bytes(need)} buffer, more than the "
                       f"{format_bytes(max_buffer)} this adapter binds)")
    advice = ""
    if refined and slices <= REFINED_PAYS_SLICES:
        plain = volume_plan(gpu, "distance", w, h)
        if plain.slices > slices:
            advice = (f"the technique distance ({plain.slices} slices here, {format_bytes(plain.nbytes)}) takes about "
                      "as many fetches or fewer")
    return VolumePlan(kind, w, h, slices, subcells, tuple(reduced), advice, volumes)


def uploaded_volume(volume: np.ndarray) -> np.ndarray:
    """A distance volume as the renderer uploads it: float16, every value rounded down (a step never grows, so
    the map stays safe). For the plain map this halves its memory; the refined-distance study measures the cost
    within +-0.2 % of the fetches (docs/maps.md). The refined kind is float16 already."""
    if volume.dtype == np.float16:
        return volume
    return volume_cpu.round_down(np.asarray(volume, np.float64), np.float16)


def volume_texture(gpu: Gpu, volume: np.ndarray, label: str) -> wgpu.GPUTexture:
    """A (Dz, H, W) volume, or (V, Dz, H, W) volumes stacked along the depth (volume v at depths [v Dz, (v + 1) Dz)),
    as an r16float 3D texture (``uploaded_volume``); converted and uploaded one depth layer at a time (no copy of
    the whole volume)."""
    h, w = volume.shape[-2:]
    depth = volume.size // (w * h)
    with allocating(gpu, label, w * h * depth * 2, "use a smaller height map"):
        texture = gpu.device.create_texture(
            label=label, size=(w, h, depth), dimension="3d", format="r16float",
            usage=wgpu.TextureUsage.TEXTURE_BINDING | wgpu.TextureUsage.COPY_DST,
        )
    layers = volume.reshape(depth, h, w)
    for z in range(depth):
        gpu.device.queue.write_texture(
            {"texture": texture, "mip_level": 0, "origin": (0, 0, z)},
            np.ascontiguousarray(uploaded_volume(layers[z])),
            {"offset": 0, "bytes_per_row": w * 2, "rows_per_image": h}, (w, h, 1),
        )
    return texture


def planned(gpu: Gpu, kind: str, depth: np.ndarray, label: str, binned: Binned | None = None) -> VolumePlan:
    """The volume plan of a height map, its reductions said in one warning line."""
    plan = volume_plan(gpu, kind, *size_of(depth), binned)
    if plan.reduced:
        log.warning(plan.note(label))
    return plan
