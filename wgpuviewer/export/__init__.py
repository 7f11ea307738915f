"""``wgpuviewer export``: a ray-search technique as one self-contained WGSL module for someone else's renderer
(``module``: the code, ``rename``: its prefixed names, ``sources``: its bindings and header, ``textures``: the maps
as it binds them, ``command``: the command).

May import: ``wgpuviewer.core``, the technique registry (and through it the technique folders' WGSL),
``wgpuviewer.relief`` (the one composer's technique pieces, the slot table) and maptools' kind registry (the
commands that make the maps); never the lab.
"""

from .module import API, Export, export_wgsl, exportable

__all__ = ["API", "Export", "export_wgsl", "exportable"]
