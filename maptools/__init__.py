"""Map generation for relief mapping: normal, complexity, maximum-pyramid and 3D distance maps from height maps.

Each kind is one folder ``maptools/kinds/KIND/``: its entry (``KIND``, found by :data:`maptools.registry.KINDS`), its
WGSL compute kernel, a CPU implementation (OpenCV/numpy) that is both the fallback and the cross-check, and the
renderer's texture slots built from it (``slot.py``). Shared once: the registry's types, the GPU runner (``gpu``),
the plain distance volume both distance kinds build (``volume``), the CLI, cache, check and I/O.

Conventions: heights are float32 (H, W) in [0, 1], 1 = top; columns are u (x, right), rows are v with
row 0 = v near 0 (v increases with the row index).

May import: ``wgpuviewer.core`` and nothing else of ``wgpuviewer`` (the renderer imports maptools, never the
other way round).
"""

from __future__ import annotations

import sys

from wgpuviewer.core.errors import NoAdapterError, UserError

from .io import validate_height

__all__ = ["generate", "validate_height", "resolve_backend", "VERSION", "KINDS"]

#: Version of the CPU reference implementations (the kinds' ``cpu.py``, ``volume/cpu.py``): part of every cache key,
#: next to the hash of the kind's composed kernel source (which tracks the GPU path by itself); bump it when a CPU
#: output changes.
VERSION = "maptools-3"

_notice_printed = False


def resolve_backend(backend: str = "auto") -> str:
    """'auto' -> 'gpu' when an adapter exists, else 'cpu' (one-line notice on stderr); 'gpu' / 'cpu' as given."""
    global _notice_printed
    if backend not in ("auto", "gpu", "cpu"):
        raise UserError(f"--backend {backend!r}: expected auto, gpu or cpu")
    if backend != "auto":
        return backend
    from . import gpu

    try:
        gpu.runner()
        return "gpu"
    except NoAdapterError:
        if not _notice_printed:
            print("notice: maptools: no GPU adapter; using the CPU implementation", file=sys.stderr)
            _notice_printed = True
        return "cpu"


def generate(kind: str, height, backend: str = "auto", **options):
    """Generate map ``kind`` from ``height`` (float (H, W) in [0, 1]) on ``backend`` (auto, gpu, cpu).

    normal -> float32 (H, W, 3); complexity -> uint8 (H, W); maxmip -> list of float32 arrays (level 0 first);
    distance -> float32 (Dz, H, W) volume; distance_refined -> float16 (V, Dz, H, W) volumes; cone -> float32 (H, W)
    ratios (docs/maps.md).
    """
    from .registry import get_kind

    k = get_kind(kind)
    opts = k.resolve(options)
    h = validate_height(height)
    fn = k.gpu if resolve_backend(backend) == "gpu" else k.cpu
    return fn(h, **opts)


def __getattr__(name):
    if name == "KINDS":
        from .registry import KINDS

        return KINDS
    raise AttributeError(name)
