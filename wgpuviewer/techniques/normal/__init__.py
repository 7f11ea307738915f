"""normal: normal mapping without displacement (``normal.wgsl``: no ray search).

May import: ``wgpuviewer.core`` and the registry (``wgpuviewer.techniques``, ``shared``).
"""

from wgpuviewer.techniques import Technique

TECHNIQUE = Technique(
    "normal", "2", "Normal mapping: per-pixel normals from the normal map, no displacement.",
    "albedo + normal fetch", ("albedo", "normal"), order=20,
)
