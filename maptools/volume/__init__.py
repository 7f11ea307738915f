"""What the two distance kinds (``distance``, ``distance_refined``) share, once: the plain volume (``cpu``: its
geometry and CPU reference; ``gpu``: its slab bake, ``distance.wgsl``; ``io``: the volume writer) and the renderer's
side of a volume (``slot``: the volume plan a height map gets on an adapter, the float16 upload). The kinds' folders
import it; it imports no kind.

May import: ``wgpuviewer.core``, numpy, wgpu and maptools' shared modules.
"""
