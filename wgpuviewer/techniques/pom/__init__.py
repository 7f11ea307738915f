"""pom: parallax occlusion mapping, the layer march with a linear finish (``pom.wgsl``; its entry is
``shared.layer_search``, steep's too).

May import: ``wgpuviewer.core`` and the registry (``wgpuviewer.techniques``, ``shared``).
"""

from wgpuviewer.techniques.shared import layer_search

TECHNIQUE = layer_search(
    "pom", "5", 50,
    "Parallax occlusion mapping: steep parallax, then linear interpolation between the last two "
    "layers (guarded against a zero denominator).",
    ({"layers": 8}, {"layers": 32}, {"layers": 256}),
)
