"""The map kinds, one folder each: ``KIND/__init__.py`` exposes ``KIND`` (its ``registry.Kind``: options, CPU and GPU
functions, comparison and tolerance, cases); beside it its CPU reference, its GPU driver and kernels, its file writer
and, where the renderer samples it, ``slot.py`` (the texture slots built from it). ``registry.KINDS`` finds them.

May import: ``wgpuviewer.core`` and maptools' shared modules; a kind folder never imports another kind's folder.
"""
