"""The texture slots a technique may sample, shared by the renderer and the probe: the one table ``MAP_SLOTS``.

A technique names what it samples in ``Technique.textures``; each name is a slot (``core.slots.MapSlot``): the
material's own textures (``albedo``, ``normal``; the renderer loads them from the scene) and its ``depth``, declared
here, then the slots of every map kind (``maptools/kinds/KIND/slot.py``'s ``SLOTS``: the maps maptools generates,
built from the depth map through maptools' registry and disk cache) and every technique's own (``Technique.slots``),
found without a list, in the order of their ``order`` numbers. A slot knows its WGSL variable and type
(``shaders.interface`` generates the binding line: binding 2 + the slot's position in ``MAP_SLOTS``) and its
bind-group layout entry.

A derived slot's ``check`` refuses a height map too large for the map on this adapter from its size alone (the
renderer calls it with a file's header size before loading or generating anything; ``build`` calls it too), naming
what exceeds which limit and the size of height map that fits: a scene has no map options to change. The distance
volumes choose their own options instead (``maptools/volume/slot.py``'s ``volume_plan``).
"""

from __future__ import annotations

import functools
import importlib
import importlib.util
import pkgutil
from collections.abc import Mapping

import numpy as np
import wgpu

from wgpuviewer.core.discovered import Discovered
from wgpuviewer.core.gpu import Gpu, create_texture, mip_chain
from wgpuviewer.core.slots import FILTERABLE_2D, TEXTURE_2D, MapSlot, check_2d, size_of

#: How far a filtered depth fetch may fall outside the range of the texels it mixes (rounding of the filter
#: weights and of the format; a float16 step near 1 is 2^-11): ``depth_range`` widens the range by this much.
DEPTH_RANGE_SLACK = 2.0 ** -10


def depth_range(depth: np.ndarray, fmt: str) -> tuple[float, float]:
    """(lowest, highest) depth of ``depth`` as the depth texture holds it (``fmt``: r32float or r16float, as
    uploaded), widened by ``DEPTH_RANGE_SLACK`` and kept in [0, 1]: every depth fetch, at any mip level (the levels
    are averages), lies within it, so the layer searches march only this range (common/trace.wgsl's relief_range).
    Non-finite depths never get here: the height readers and the probe refuse them."""
    d = np.asarray(depth, np.float32)  # the upload's path: float32 first, then the texture's format
    if fmt == "r16float":
        d = d.astype(np.float16).astype(np.float32)
    lo, hi = float(d.min()), float(d.max())
    return max(0.0, lo - DEPTH_RANGE_SLACK), min(1.0, hi + DEPTH_RANGE_SLACK)


def _check_depth(gpu: Gpu, w: int, h: int) -> None:
    check_2d(gpu, w, h)


def _depth(gpu: Gpu, depth: np.ndarray, height_scale: float, label: str) -> wgpu.GPUTexture:
    _check_depth(gpu, *size_of(depth))
    return create_texture(gpu, mip_chain(depth), gpu.depth_format, label)


#: The material's slots: its own textures and its depth map, first in the binding order.
MATERIAL_SLOTS = (
    MapSlot("albedo", TEXTURE_2D, FILTERABLE_2D, None, "linear RGB albedo (rgba16float), mip chain"),
    MapSlot("normal", TEXTURE_2D, FILTERABLE_2D, None, "tangent-space normals as n * 0.5 + 0.5 (rgba8unorm)"),
    MapSlot("depth", TEXTURE_2D, FILTERABLE_2D, _depth, "D = 1 - height, mip chain (r32float, or r16float)",
            check=_check_depth),
)


@functools.cache
def _kind_slots() -> tuple[MapSlot, ...]:
    """Every map kind's slots: ``SLOTS`` of each ``maptools/kinds/*/slot.py``."""
    from maptools import kinds

    found: list[MapSlot] = []
    for info in pkgutil.iter_modules(kinds.__path__):
        if info.ispkg and importlib.util.find_spec(f"{kinds.__name__}.{info.name}.slot") is not None:
            found += importlib.import_module(f"{kinds.__name__}.{info.name}.slot").SLOTS
    return tuple(found)


def _technique_slots() -> tuple[MapSlot, ...]:
    from wgpuviewer.techniques import TECHNIQUES

    return tuple(slot for t in TECHNIQUES.values() for slot in t.slots)


def _slot_table() -> dict[str, MapSlot]:
    """Name -> MapSlot in binding order: the material's, then the map kinds' and the techniques' by (order, name)."""
    derived = sorted([*_kind_slots(), *_technique_slots()], key=lambda s: (s.order, s.name))
    table: dict[str, MapSlot] = {}
    for slot in (*MATERIAL_SLOTS, *derived):
        if slot.name in table:
            raise ValueError(f"texture slot {slot.name!r} is declared twice")
        table[slot.name] = slot
    return table


#: The one table of slots, collected on first use (technique discovery imports modules that import this one) and
#: again when the techniques' slots change (a test adds a throw-away technique folder that way).
MAP_SLOTS: Mapping[str, MapSlot] = Discovered("MAP_SLOTS", _slot_table, _technique_slots)

#: @group(1) bindings: the TraceParams uniform, the material sampler, then the texture slots.
PARAMS_BINDING, SAMPLER_BINDING, FIRST_SLOT_BINDING = 0, 1, 2


def binding(name: str) -> int:
    """@group(1) @binding(N) of a texture slot."""
    return FIRST_SLOT_BINDING + list(MAP_SLOTS).index(name)


def layout_entries(names, visibility) -> list[dict]:
    """Bind-group layout entries for the texture slots ``names``."""
    return [{"binding": binding(n), "visibility": visibility, **MAP_SLOTS[n].layout} for n in names]


def volume_plan(gpu: Gpu, kind: str, w: int, h: int):
    """The ``VolumePlan`` a w x h height map's volume of map kind ``kind`` (a distance kind) gets on this adapter:
    its slot module's ``plan`` (``maptools/kinds/KIND/slot.py``)."""
    return importlib.import_module(f"maptools.kinds.{kind}.slot").plan(gpu, w, h)


def height_scale_adjustable(textures) -> bool:
    """Whether a technique sampling ``textures`` may trace at another height scale than its maps were built for."""
    return not any(MAP_SLOTS[t].scale_bound for t in textures)
