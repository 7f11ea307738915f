"""basic: plain texturing, the baseline every cost is compared with (``basic.wgsl``: no ray search).

May import: ``wgpuviewer.core`` and the registry (``wgpuviewer.techniques``, ``shared``).
"""

from wgpuviewer.techniques import Technique

TECHNIQUE = Technique(
    "basic", "1", "Basic texturing: albedo at the interpolated UV, flat surface normal.",
    "1 albedo fetch", ("albedo",), order=10,
)
