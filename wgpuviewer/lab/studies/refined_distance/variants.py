"""The refined-distance study's map variants: the plain maps before and now, their compact storages, the refined
maps' bins with the paper's visibility condition off and on, and which registered technique renders each."""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from maptools.kinds.distance_refined.slot import REFINED_BANDS, REFINED_MAX_ANGLE, REFINED_SECTORS
from maptools.registry import get_kind
from maptools.volume.slot import uploaded_volume

#: The baseline's kind: not a maptools kind, built by baseline.plain_before (uncached: seconds).
BEFORE = "maptools-2 plain"


@dataclass(frozen=True)
class Variant:
    name: str
    kind: str  # maptools kind
    options: dict  # beyond slices and height_scale
    technique: str = ""  # the registered technique that renders exactly this map, if any
    storage: str = ""  # a compact storage of the values (STORAGES), "" as maptools stores them

    def bins(self) -> dict:
        """The tracer's view of the map: sectors, bands and max_angle (refined kind) or nothing (plain)."""
        if self.kind != "distance_refined":
            return {}
        return {k: self.options[k] for k in ("sectors", "bands", "max_angle")}


#: Donnelly stored his distances in 8 bits: over [0, EIGHT_BIT_RANGE] texels, larger ones stored as the range.
EIGHT_BIT_RANGE = 16.0


def _eight_bit(v: np.ndarray) -> np.ndarray:
    v = np.asarray(v, np.float64)
    return np.minimum(np.floor(np.minimum(v, EIGHT_BIT_RANGE) / EIGHT_BIT_RANGE * 255.0) * EIGHT_BIT_RANGE / 255.0, v)


#: Storages of the plain map: each value rounded DOWN to what the storage holds (a step never grows, so safety
#: holds), and its bytes per value: float16 (r16float, what the renderer uploads: relief.maps.uploaded_volume) and
#: Donnelly's 8 bits (r8unorm); maptools' own float32 is the variant without a storage.
STORAGES = {"float16": (lambda v: uploaded_volume(v).astype(np.float64), 2), "8-bit": (_eight_bit, 1)}

#: The paper's visibility condition as maptools names it (an option of the distance_refined kind).
VISIBILITY = "visibility"


def _refined(sectors: int, bands: int, technique: str = "", visibility: str = "") -> Variant:
    """A refined-map variant; ``visibility`` "on"/"off" sets the paper's condition, "" leaves the kind's default."""
    name = "single cone" if sectors == bands == 1 else f"{sectors} sectors x {bands} bands"
    options = {"sectors": sectors, "bands": bands, "max_angle": REFINED_MAX_ANGLE}
    if visibility:
        name += f", visibility {visibility}"
        options[VISIBILITY] = visibility
    return Variant(name, "distance_refined", options, technique)


VARIANTS = (
    Variant("plain before (maptools-2)", BEFORE, {}),
    Variant("plain K=1", "distance", {"subcells": 1}),
    Variant("plain K=4", "distance", {"subcells": 4}, "distance", storage="float16"),
    Variant("plain K=4, float32", "distance", {"subcells": 4}),
    Variant("plain K=4, 8-bit", "distance", {"subcells": 4}, storage="8-bit"),
    _refined(1, 1),
    _refined(8, 1),
    _refined(1, REFINED_BANDS),
    _refined(2, REFINED_BANDS),
    _refined(REFINED_SECTORS, REFINED_BANDS, "distance_refined"),
    _refined(1, 1, visibility="on"),
    _refined(REFINED_SECTORS, REFINED_BANDS, visibility="on"),
)
PRODUCT = VARIANTS[-3].name
SINGLE_CONE = next(v.name for v in VARIANTS if v.kind == "distance_refined")
PLAIN = "plain K=4"  # the product's `distance` map: the ratios' denominator
#: The paper's condition: (its map with the condition, the same map without), single cone and binned.
CONDITION_PAIRS = ((VARIANTS[-2].name, SINGLE_CONE), (VARIANTS[-1].name, PRODUCT))


def variants() -> tuple[Variant, ...]:
    """The variants measured: every refined one with its condition set ("off" where VARIANTS leaves it out), and
    the `distance_refined` technique on the product's bins with the kind's default condition (what the renderer
    builds)."""
    default = next(o.default for o in get_kind("distance_refined").options if o.name == VISIBILITY)
    out = []
    for v in VARIANTS:
        if v.kind != "distance_refined":
            out.append(v)
            continue
        opts = {VISIBILITY: "off", **v.options}
        product_bins = (opts["sectors"], opts["bands"]) == (REFINED_SECTORS, REFINED_BANDS)
        technique = "distance_refined" if product_bins and opts[VISIBILITY] == default else ""
        out.append(replace(v, options=opts, technique=technique))
    return tuple(out)


#: Donnelly's regime is measured on these variants (those this maptools builds).
#: The plain map in maptools' float32 and in Donnelly's 8 bits (the product's is float16: PLAIN).
OTHER_STORAGES = ("plain K=4, float32", "plain K=4, 8-bit")
DONNELLY_VARIANTS = (PLAIN, SINGLE_CONE, VARIANTS[-2].name, PRODUCT, VARIANTS[-1].name, *OTHER_STORAGES)
