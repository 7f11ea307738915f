"""Content-addressed cache of generated maps, for the renderer.

Key = sha256 of (array bytes, shape, dtype, kind, resolved options, maptools VERSION). The backend is not
part of the key: GPU and CPU results agree within each kind's documented tolerance.
Files: ``$WGPUVIEWER_CACHE_DIR`` (default ``~/.cache/wgpuviewer/maps``) / KIND / KEY[:2] / KEY.npy|.npz,
written atomically (a concurrent reader never sees a partial file).
"""

from __future__ import annotations

import hashlib
import json
import os
from pathlib import Path

import numpy as np

from wgpuviewer.core.io import atomic_open

from . import VERSION, generate, validate_height
from .io import read_maxmip, write_maxmip
from .registry import get_kind

CACHE_ENV = "WGPUVIEWER_CACHE_DIR"


def cache_dir() -> Path:
    return Path(os.environ.get(CACHE_ENV) or Path.home() / ".cache" / "wgpuviewer" / "maps")


def cache_key(kind: str, height: np.ndarray, options: dict) -> str:
    a = np.ascontiguousarray(height)
    h = hashlib.sha256()
    h.update(json.dumps({"shape": list(a.shape), "dtype": str(a.dtype), "kind": kind,
                         "options": options, "version": VERSION}, sort_keys=True).encode())
    h.update(memoryview(a).cast("B"))  # the bytes as they are, no copy
    return h.hexdigest()


def cache_path(kind: str, key: str) -> Path:
    return cache_dir() / kind / key[:2] / (key + (".npz" if kind == "maxmip" else ".npy"))


def cached_generate(kind: str, height, backend: str = "auto", **options):
    """Like :func:`maptools.generate`, but returns a cached result when the same input was seen before."""
    k = get_kind(kind)
    opts = k.resolve(options)
    h = validate_height(height)
    path = cache_path(kind, cache_key(kind, h, opts))
    if path.is_file():
        try:
            return read_maxmip(path) if kind == "maxmip" else np.load(path, allow_pickle=False)
        except Exception:  # noqa: BLE001 - a damaged cache entry is regenerated
            pass
    result = generate(kind, h, backend=backend, **opts)
    with atomic_open(path) as f:
        if kind == "maxmip":
            write_maxmip(f, result, ".npz")
        else:
            np.save(f, result)
    return result
