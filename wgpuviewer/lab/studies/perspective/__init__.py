"""The perspective-correct texturing study (Romanyuk & Dudnyk, perspective texturing: Heckbert's formulas with their
incremental and parallel forms): for screen pixel (x, y) of a planar polygon
``u = (A1 x + B1 y + C1) / (D x + E y + F)``, and the same for v; every way of evaluating it along a span, in
float32 and float64, on the CPU (numpy, an exact float32 emulation; compiled scalar and SIMD loops, numba) and the
GPU (WGSL compute kernels), measured for speed and for texture-coordinate error (screen pixels, texels) against
float64, with a recommendation of which method to use where.

- ``command``: ``wgpuviewer perspective --out DIR`` (``STUDY``);
- ``geometry``: the textured quad under a perspective camera, its coefficients from the projective
  texture-to-screen map (float64), the spans, the float64 reference;
- ``arith``: float32/float64 arithmetic that rounds every operation and counts them (the operation counts);
- ``methods``: the numpy form of every method and mitigation (the registry ``METHODS``);
- ``kernels``: the same methods as WGSL compute kernels (``wgsl/studies/perspective/``), run and timed;
- ``compiled``: the same methods as compiled loops (numba; a scalar and a SIMD build), run and timed per texel;
- ``hardware``: the uv the rasteriser interpolates for the same quad (the renderer's ``uv`` data);
- ``tieback``: large texture coordinates through the relief techniques' probe;
- ``run``, ``report`` and ``plots``: the sweeps, ``results.csv``, ``report.md``, the plots.

May import: ``wgpuviewer.core``, ``wgpuviewer.lab.harness``, ``wgpuviewer.relief``, the scene modules (``camera``,
``meshes``, ``scene``); the CLI registers ``STUDY``.
"""

from .command import STUDY

__all__ = ["STUDY"]
