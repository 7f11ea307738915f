"""Relief mapping itself: the technique registry (techniques), the texture slots and derived maps they sample
(maps), how their shader modules are generated and composed (shaders), drawing a scene (renderer, with its parts
material_textures, uniforms, pipelines and targets; output), running a technique's ray search on given rays
(probe), the float64 exact first hit (reference), the comparison of the two (accuracy) turntables (turntable: orbit
cameras and the GIF/MP4 writer) and warming the map cache ahead of a run (warm).

May import: ``wgpuviewer.core``, the scene modules (``wgpuviewer.scene``, ``textures``, ``meshes``, ``camera``) and
``maptools`` (for the derived maps); never the viewer, the benchmark or the studies.
"""
