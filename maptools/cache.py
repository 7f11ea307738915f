"""Content-addressed cache of generated maps, for the renderer.

Key = sha256 of (array bytes, shape, dtype, kind, resolved options, the kind's kernel source hash, maptools
VERSION, the entry format): an edited kernel, or a file it includes, gets new keys by itself; VERSION tracks the CPU
reference. Keys of kinds outside the registry (the renderer's auto table) hold their own version in their options.
The backend is not part of the key: GPU and CPU results agree within each kind's documented tolerance.
Files: ``$WGPUVIEWER_CACHE_DIR`` (default ``~/.cache/wgpuviewer/maps``) / KIND / KEY[:2] / KEY.npz, written
atomically (a concurrent reader never sees a partial file). Each entry holds its map (``map``, or ``level0`` ...
for a list of arrays), its key and a sha256 of both; a read checks them, and an entry that fails (overwritten,
truncated, another map's file) is rebuilt with one warning line saying so.

Size: at most ``$WGPUVIEWER_CACHE_MAX`` bytes (default 2G; suffixes K, M, G, T; 0 turns the cap off); after
each write the least recently used maps (a hit touches its file) are evicted until the cache fits. Both variables
are parsed by ``wgpuviewer.core.env``.
``maptools cache info`` shows it, ``maptools cache clean [--older-than 7d]`` empties it; both refuse a cache path
that is not a folder. A cache folder that cannot be written is a warning for the renderer (maps are then rebuilt
each run), never an error.

Named maps: inside ``serving({kind: (path, where)})`` (the renderer, around the build of a material whose scene names
precomputed maps), ``cached_generate`` of that kind serves the file instead, once its batch record
(``wgpuviewer.core.sidecar``) says it is the map asked for: the same kind, options and maptools version, and the
file's bytes as the batch wrote them; otherwise a UserError says, against ``where``, what differs and the batch
command that builds the right map. That the map was built from the material's height file is the scene's check.
``recording()`` lists what the cache served (built, from the cache, from a named file): ``wgpuviewer warm`` reports
it, tests count with it.
"""

from __future__ import annotations

import contextlib
import contextvars
import hashlib
import json
import logging
import os
import stat
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from wgpuviewer.core import env
from wgpuviewer.core.errors import FileError, UserError
from wgpuviewer.core.gpu import format_bytes
from wgpuviewer.core.io import WriteError, atomic_open, remove_abandoned_temps
from wgpuviewer.core.sidecar import read_record

from . import VERSION, generate, validate_height
from .io import read_map
from .registry import KINDS, get_kind

CACHE_ENV = env.CACHE_DIR.name
CACHE_MAX_ENV = env.CACHE_MAX.name
#: The entry layout (module docstring); part of every key, so entries of an older layout are never read (they age
#: out through eviction or ``cache clean``).
ENTRY_FORMAT = 2
#: Member names an entry keeps next to its map.
_KEY, _CHECKSUM = "key", "sha256"

log = logging.getLogger("maptools.cache")
_warned: set[str] = set()


def cache_dir() -> Path:
    return env.CACHE_DIR.value() or Path.home() / ".cache" / "wgpuviewer" / "maps"


def cache_limit() -> int:
    """The size cap in bytes (0: none)."""
    return env.CACHE_MAX.value()


def cache_key(kind: str, height: np.ndarray, options: dict) -> str:
    a = np.ascontiguousarray(height)
    h = hashlib.sha256()
    h.update(json.dumps({"shape": list(a.shape), "dtype": str(a.dtype), "kind": kind,
                         "options": options, "version": VERSION, "format": ENTRY_FORMAT,
                         "kernels": KINDS[kind].source_hash() if kind in KINDS else None}, sort_keys=True).encode())
    h.update(memoryview(a).cast("B"))  # the bytes as they are, no copy
    return h.hexdigest()


def cache_path(kind: str, key: str) -> Path:
    return cache_dir() / kind / key[:2] / (key + ".npz")


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


def require_folder() -> Path:
    """The cache folder for ``cache info``/``clean``: one that does not exist yet is an empty cache; a path that is
    a file, or lies under one, is a UserError (not "0 maps")."""
    root = cache_dir()
    fix = f"set ${CACHE_ENV} to a folder, or unset it for the default {env.CACHE_DIR.default_text}"
    try:
        mode = root.stat().st_mode
    except FileNotFoundError:
        return root
    except NotADirectoryError:
        raise UserError(f"map cache {root}: part of the path is a file, not a folder; {fix}") from None
    except OSError as error:
        raise UserError(f"map cache {root}: cannot read ({error.strerror or error}); {fix}") from None
    if not stat.S_ISDIR(mode):
        raise UserError(f"map cache {root} is not a folder; {fix}")
    return root


def clean(older_than: float | None = None) -> list[Entry]:
    """Remove every cached map, or those not used for more than ``older_than`` seconds; abandoned temp files
    (of killed writers) go too. Returns the maps removed."""
    require_folder()
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


class DamagedEntry(Exception):
    """A cache entry that does not hold what its key names; the message says how."""


def _members(result) -> dict[str, np.ndarray]:
    """An entry's arrays by name: one array as ``map``, a list of arrays (maxmip) as ``level0`` ... in order."""
    if isinstance(result, np.ndarray):
        return {"map": result}
    return {f"level{i}": np.asarray(a) for i, a in enumerate(result)}


def _checksum(key: str, members: dict[str, np.ndarray]) -> str:
    h = hashlib.sha256(key.encode())
    for name, a in members.items():
        a = np.ascontiguousarray(a)
        h.update(f"{name} {a.dtype.str} {a.shape}".encode())
        h.update(a.reshape(-1).view(np.uint8))
    return h.hexdigest()


def read_entry(path: Path, key: str):
    """The map of the entry at ``path``, checked against ``key`` and its checksum; DamagedEntry otherwise."""
    try:
        with np.load(path, allow_pickle=False) as z:
            stored = {name: z[name] for name in z.files}
    except Exception as error:  # noqa: BLE001 - whatever a cut or overwritten file raises
        raise DamagedEntry(f"unreadable: {type(error).__name__}: {error}") from None
    if _KEY not in stored or _CHECKSUM not in stored:
        raise DamagedEntry("no key or checksum in it")
    if str(stored.pop(_KEY)) != key:
        raise DamagedEntry("it holds another map")
    checksum = str(stored.pop(_CHECKSUM))
    if "map" in stored and len(stored) == 1:
        result = stored["map"]
    else:
        try:
            result = [stored[f"level{i}"] for i in range(len(stored))]
        except KeyError:
            raise DamagedEntry(f"unexpected arrays {', '.join(sorted(stored))}") from None
    if _checksum(key, _members(result)) != checksum:
        raise DamagedEntry("checksum mismatch: its data changed after it was written")
    return result


def write_entry(f, key: str, result) -> None:
    """An entry of ``result`` under ``key`` into the binary file ``f`` (read back by ``read_entry``)."""
    members = _members(result)
    np.savez(f, **members, **{_KEY: np.array(key), _CHECKSUM: np.array(_checksum(key, members))})


@dataclass(frozen=True)
class Served:
    """One map the cache handed out: its kind, and where it came from: "built" (and stored), "cache" (an entry)
    or "file" (a named map)."""

    kind: str
    source: str


_recorders: contextvars.ContextVar[tuple[list[Served], ...]] = contextvars.ContextVar("map_recorders", default=())
_named: contextvars.ContextVar[dict[str, tuple[Path, str]] | None] = contextvars.ContextVar("named_maps", default=None)


def _served(kind: str, source: str) -> None:
    for served in _recorders.get():
        served.append(Served(kind, source))


@contextlib.contextmanager
def recording() -> Iterator[list[Served]]:
    """The maps served inside the block, in order (this thread's; nested blocks each see theirs)."""
    served: list[Served] = []
    token = _recorders.set((*_recorders.get(), served))
    try:
        yield served
    finally:
        _recorders.reset(token)


@contextlib.contextmanager
def serving(maps: dict[str, tuple[Path, str]]) -> Iterator[None]:
    """Inside the block, ``cached_generate`` of a kind in ``maps`` serves that file (module docstring); ``where``
    names it in errors (the scene key)."""
    token = _named.set(dict(maps))
    try:
        yield
    finally:
        _named.reset(token)


def _option_text(options: dict, names) -> str:
    return ", ".join(f"{name}={options[name]}" for name in names)


def named_map(kind: str, path: Path, where: str, shape: tuple[int, int], options: dict) -> np.ndarray:
    """The map of ``kind`` in the file at ``path`` when its record matches the request (``options``: resolved; a
    map of ``shape`` (H, W)); a UserError against ``where`` otherwise."""
    try:
        record = read_record(path)
    except FileError as error:
        raise UserError(f"{where}: {error}") from None
    rebuild = f"maptools batch {record.input} -o {path.parent} --kinds {kind}"
    if record.kind != kind:
        raise UserError(f"{where}: is a {record.kind} map (its record says so); expected a {kind} map")
    if record.version != VERSION:
        raise UserError(f"{where}: built by {record.version}, this is {VERSION}: rebuild it ({rebuild} --force)")
    try:
        found = get_kind(kind).resolve(record.options)
    except UserError as error:
        raise UserError(f"{where}: its record's options do not fit this maptools ({error}): rebuild it "
                        f"({rebuild} --force)") from None
    differ = [name for name in options if found[name] != options[name]]
    if differ:
        defaults = get_kind(kind).resolve({})  # the batch's: every other option the renderer needs is set too
        sets = " ".join(f"--set {kind}.{name}={value}" for name, value in options.items() if value != defaults[name])
        raise UserError(f"{where}: built with {_option_text(found, differ)}; the renderer needs "
                        f"{_option_text(options, differ)}: rebuild it ({rebuild} {sets})")
    try:
        data = path.read_bytes()
    except OSError as error:
        raise UserError(f"{where}: cannot read {path} ({error.strerror or error})") from None
    if hashlib.sha256(data).hexdigest() != record.output_sha256:
        raise UserError(f"{where}: {path.name} changed after maptools batch wrote it (its sha256 is not its "
                        f"record's): rebuild it ({rebuild} --force)")
    try:
        result = read_map(kind, data, path.suffix.lower())
    except UserError as error:
        raise UserError(f"{where}: {error}") from None
    if result.shape[-2:] != tuple(shape):
        raise UserError(f"{where}: a map of {result.shape[-1]}x{result.shape[-2]} texels; the height map is "
                        f"{shape[1]}x{shape[0]}")
    _served(kind, "file")
    return result


def cached(kind: str, key: str, build: Callable[[], object]):
    """The map cached as ``kind``/``key`` when its entry checks out (``read_entry``), else ``build()``'s result,
    stored (a damaged entry: rebuilt, with one warning line saying so)."""
    path = cache_path(kind, key)
    if path.is_file():
        try:
            result = read_entry(path, key)
        except DamagedEntry as damage:
            log.warning(f"map cache: {path} is damaged ({damage}); rebuilding it")
        else:
            with contextlib.suppress(OSError):  # a read-only cache still serves
                os.utime(path)  # a hit: most recently used now
            _served(kind, "cache")
            return result
    limit = cache_limit()  # a bad $WGPUVIEWER_CACHE_MAX is a user error before the work, not after it
    result = build()
    _served(kind, "built")
    try:
        with atomic_open(path) as f:
            write_entry(f, key, result)
    except WriteError as error:  # read-only, full, not a folder: the map is still good
        _warn_once(error.strerror)
        return result
    evict(limit, keep=path)
    return result


def cached_generate(kind: str, height, backend: str = "auto", **options):
    """Like :func:`maptools.generate`, but returns a cached result when the same input was seen before, or the named
    map of the kind inside ``serving``."""
    opts = get_kind(kind).resolve(options)
    h = validate_height(height)
    named = (_named.get() or {}).get(kind)
    if named is not None:
        return named_map(kind, *named, h.shape, opts)
    return cached(kind, cache_key(kind, h, opts), lambda: generate(kind, h, backend=backend, **opts))


def _age(seconds: float) -> str:
    for unit, length in (("d", 86400), ("h", 3600), ("min", 60)):
        if seconds >= length:
            return f"{seconds / length:.0f} {unit}"
    return f"{seconds:.0f} s"


def describe() -> str:
    """``maptools cache info``: where, how big, the cap, per kind."""
    require_folder()
    found = entries()
    limit = cache_limit()
    source = f"${CACHE_ENV}" if env.CACHE_DIR.raw() else f"default; set ${CACHE_ENV} to move it"
    cap = (f"{format_bytes(limit)} (${CACHE_MAX_ENV}, default {env.CACHE_MAX.default_text})" if limit
           else f"none (${CACHE_MAX_ENV}=0)")
    lines = [f"map cache: {cache_dir()} ({source})",
             f"size cap: {cap}; the least recently used maps are evicted beyond it"]
    kinds: dict[str, list[Entry]] = {}
    for e in found:
        kinds.setdefault(e.kind, []).append(e)
    now = time.time()
    for kind, items in sorted(kinds.items()):
        lines.append(f"  {kind:<17} {len(items):>5} maps  {format_bytes(sum(e.size for e in items)):>10}  "
                     f"last used {_age(now - items[-1].last_used)} ago")
    total = sum(e.size for e in found)
    lines.append(f"total: {len(found)} maps, {format_bytes(total)}" + (f" ({100 * total / limit:.0f} % of the cap)"
                                                                 if limit else ""))
    return "\n".join(lines)
