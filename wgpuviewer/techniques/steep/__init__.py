"""steep: steep parallax mapping, the layer march stopping at the first layer below the surface (``steep.wgsl``;
its entry is ``shared.layer_search``, pom's too).

May import: ``wgpuviewer.core`` and the registry (``wgpuviewer.techniques``, ``shared``).
"""

from wgpuviewer.techniques.shared import layer_search

TECHNIQUE = layer_search(
    "steep", "4", 40,
    "Steep parallax mapping: march N depth layers along the view ray, stop at the first layer "
    "below the surface.",
    ({"layers": 32},),
)
