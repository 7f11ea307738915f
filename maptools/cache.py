"""Content-addressed cache of generated maps, for the renderer.

Key = sha256 of (array bytes, shape, dtype, kind, resolved options, the kind's kernel source hash, maptools
VERSION): an edited kernel, or a file it includes, gets new keys by itself; VERSION tracks the CPU reference. Keys of
kinds outside the registry (the renderer's auto table) hold their own version in their options. The backend is not
part of the key: GPU and CPU results agree within each kind's documented tolerance.
Files: ``$WGPUVIEWER_CACHE_DIR`` (default ``~/.cache/wgpuviewer/maps``) / KIND / KEY[:2] / KEY.npy|.npz,
written atomically (a concurrent reader never sees a partial file).

Size: at most ``$WGPUVIEWER_CACHE_MAX`` bytes (default 2G; suffixes K, M, G, T; 0 turns the cap off); after
each write the least recently used maps (a hit touches its file) are evicted until the cache fits.
``maptools cache info`` shows it, ``maptools cache clean [--older-than 7d]`` empties it.
A cache folder that cannot be written is a warning (maps are then rebuilt each run), never an error.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import logging
import os
import re
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from wgpuviewer.core.errors import UserError
from wgpuviewer.core.io import WriteError, atomic_open, remove_abandoned_temps

from . import VERSION, generate, validate_height
from .io import read_maxmip, write_maxmip
from .registry import KINDS, get_kind

CACHE_ENV = "WGPUVIEWER_CACHE_DIR"
CACHE_MAX_ENV = "WGPUVIEWER_CACHE_MAX"
DEFAULT_CACHE_MAX = "2G"
_UNITS = {"": 1, "K": 2**10, "M": 2**20, "G": 2**30, "T": 2**40}

log = logging.getLogger("maptools.cache")
_warned: set[str] = set()


def cache_dir() -> Path:
    return Path(os.environ.get(CACHE_ENV) or Path.home() / ".cache" / "wgpuviewer" / "maps")


def parse_size(text: str, what: str) -> int:
    """'500M', '2G', '1.5T', '123' (bytes), '2GiB' -> bytes; a UserError naming ``what`` otherwise."""
    match = re.fullmatch(r"\s*(\d+(?:\.\d*)?)\s*([KMGT]?)(?:I?B)?\s*", text, re.IGNORECASE)
    if not match:
        raise UserError(f"{what} = {text!r}: expected a size such as 500M, 2G or 0 (no cap)")
    return int(float(match[1]) * _UNITS[match[2].upper()])


def cache_limit() -> int:
    """The size cap in bytes (0: none)."""
    return parse_size(os.environ.get(CACHE_MAX_ENV) or DEFAULT_CACHE_MAX, f"${CACHE_MAX_ENV}")


def cache_key(kind: str, height: np.ndarray, options: dict) -> str:
    a = np.ascontiguousarray(height)
    h = hashlib.sha256()
    h.update(json.dumps({"shape": list(a.shape), "dtype": str(a.dtype), "kind": kind,
                         "options": options, "version": VERSION,
                         "kernels": KINDS[kind].source_hash() if kind in KINDS else None}, sort_keys=True).encode())
    h.update(memoryview(a).cast("B"))  # the bytes as they are, no copy
    return h.hexdigest()


def cache_path(kind: str, key: str) -> Path:
    return cache_dir() / kind / key[:2] / (key + (".npz" if kind == "maxmip" else ".npy"))


@dataclass(frozen=True)
class Entry:
    path: Path
    kind: str
    size: int
    last_used: float  # mtime: written, or touched by a hit


def entries() -> list[Entry]:
    """The cached maps (temp files of writers excluded), least recently used first."""
    root = cache_dir()
    found = []
    for path in root.glob("*/*/*.np[yz]"):
        try:
            info = path.stat()
        except OSError:
            continue
        found.append(Entry(path, path.parent.parent.name, info.st_size, info.st_mtime))
    return sorted(found, key=lambda e: e.last_used)


def _remove(entry: Entry) -> bool:
    try:
        entry.path.unlink()
        return True
    except OSError:
        return False


def evict(limit: int, keep: Path | None = None) -> list[Entry]:
    """Remove least recently used maps until the cache holds at most ``limit`` bytes (0: no cap); ``keep``
    (the map just written) stays. Returns what was removed."""
    if limit <= 0:
        return []
    found = entries()
    total = sum(e.size for e in found)
    removed = []
    for entry in found:
        if total <= limit:
            break
        if entry.path != keep and _remove(entry):
            total -= entry.size
            removed.append(entry)
    return removed


def clean(older_than: float | None = None) -> list[Entry]:
    """Remove every cached map, or those not used for more than ``older_than`` seconds; abandoned temp files
    (of killed writers) go too. Returns the maps removed."""
    cutoff = None if older_than is None else time.time() - older_than
    removed = [e for e in entries() if (cutoff is None or e.last_used < cutoff) and _remove(e)]
    for folder in cache_dir().glob("*/*"):
        remove_abandoned_temps(folder)
    return removed


def _warn_once(reason: str) -> None:
    folder = str(cache_dir())
    if folder not in _warned:
        _warned.add(folder)
        log.warning(f"map cache {folder} cannot be written ({reason}); maps are rebuilt on every run: "
                    f"set {CACHE_ENV} to a writable folder")


def _load(kind: str, path: Path):
    result = read_maxmip(path) if kind == "maxmip" else np.load(path, allow_pickle=False)
    with contextlib.suppress(OSError):  # a read-only cache still serves
        os.utime(path)  # a hit: most recently used now
    return result


def cached_generate(kind: str, height, backend: str = "auto", **options):
    """Like :func:`maptools.generate`, but returns a cached result when the same input was seen before."""
    k = get_kind(kind)
    opts = k.resolve(options)
    h = validate_height(height)
    path = cache_path(kind, cache_key(kind, h, opts))
    if path.is_file():
        try:
            return _load(kind, path)
        except Exception:  # noqa: BLE001 - a damaged cache entry is regenerated
            pass
    limit = cache_limit()  # a bad $WGPUVIEWER_CACHE_MAX is a user error before the work, not after it
    result = generate(kind, h, backend=backend, **opts)
    try:
        with atomic_open(path) as f:
            if kind == "maxmip":
                write_maxmip(f, result, ".npz")
            else:
                np.save(f, result)
    except WriteError as error:  # read-only, full, not a folder: the map is still good
        _warn_once(error.strerror)
        return result
    evict(limit, keep=path)
    return result


def _size(n: float) -> str:
    for unit in ("B", "KiB", "MiB", "GiB"):
        if n < 1024 or unit == "GiB":
            return f"{n:.0f} {unit}" if unit == "B" else f"{n:.1f} {unit}"
        n /= 1024
    return f"{n:.1f} TiB"


def _age(seconds: float) -> str:
    for unit, length in (("d", 86400), ("h", 3600), ("min", 60)):
        if seconds >= length:
            return f"{seconds / length:.0f} {unit}"
    return f"{seconds:.0f} s"


def describe() -> str:
    """``maptools cache info``: where, how big, the cap, per kind."""
    found = entries()
    limit = cache_limit()
    source = f"${CACHE_ENV}" if os.environ.get(CACHE_ENV) else f"default; set ${CACHE_ENV} to move it"
    cap = f"{_size(limit)} (${CACHE_MAX_ENV}, default {DEFAULT_CACHE_MAX})" if limit else f"none (${CACHE_MAX_ENV}=0)"
    lines = [f"map cache: {cache_dir()} ({source})",
             f"size cap: {cap}; the least recently used maps are evicted beyond it"]
    kinds: dict[str, list[Entry]] = {}
    for e in found:
        kinds.setdefault(e.kind, []).append(e)
    now = time.time()
    for kind, items in sorted(kinds.items()):
        lines.append(f"  {kind:<17} {len(items):>5} maps  {_size(sum(e.size for e in items)):>10}  "
                     f"last used {_age(now - items[-1].last_used)} ago")
    total = sum(e.size for e in found)
    lines.append(f"total: {len(found)} maps, {_size(total)}" + (f" ({100 * total / limit:.0f} % of the cap)"
                                                                 if limit else ""))
    return "\n".join(lines)
