"""Atomic file writes: every output of the project (renders, maps, reports, settings, caches) goes through
``atomic_open``, so a reader never sees a partial file, even after ``kill -9`` or a full disk (the results tables
of bench and the studies too: ``wgpuviewer.lab.harness.table``).

Every way a write can fail that the user can fix (the path is a folder, the disk is full, the folder is read-only
or not ours, a parent is a file) is a one-line ``UserError`` naming the path and the fix; nothing is left behind.
``output_dir`` checks an output folder up front (not empty, not an existing file, creatable and writable) and
creates it; when it cannot, it leaves nothing behind.

The temp file of ``NAME`` is ``.NAME.XXXXXXXX.tmp`` (``TEMP_NAME``: eight characters of ``tempfile.mkstemp``'s
alphabet). While it is written it is locked (``flock``) by its writer; ``remove_stale_temps`` and
``remove_abandoned_temps`` remove only files of exactly that pattern that no live process holds, so concurrent
writers into one folder never delete each other's work, and a user's own ``*.tmp`` files are never touched.
"""

from __future__ import annotations

import contextlib
import errno
import glob
import os
import re
import tempfile
import time
from pathlib import Path

from .errors import FileError, UserError

try:
    import fcntl
except ImportError:  # Windows: an open file cannot be removed there anyway
    fcntl = None

#: The temp files ``atomic_open`` makes: ``.`` + the target's name + ``.`` + mkstemp's eight random characters +
#: ``.tmp`` (``_locked_temp``); the only files the stale-temp cleaners remove.
TEMP_NAME = re.compile(r"\.(?P<target>.+)\.[a-z0-9_]{8}\.tmp")
#: Without flock (Windows), temps older than this are taken as abandoned.
UNLOCKED_TEMP_AGE = 24 * 3600.0

_FIXES = {
    errno.ENOSPC: "the disk is full; free some space or choose another folder",
    errno.EROFS: "the file system is read-only; choose another folder",
    errno.EACCES: "permission denied; choose a folder you can write to",
    errno.EPERM: "permission denied; choose a folder you can write to",
    errno.ENOTDIR: "a part of the path is a file, not a folder; choose another path",
    errno.EEXIST: "a part of the path is a file, not a folder; choose another path",
    errno.EISDIR: "it is a directory; give a file name",
    errno.EFBIG: "the file is too large for this file system; choose another folder",
    errno.ENAMETOOLONG: "the name is too long; choose a shorter path",
}
if hasattr(errno, "EDQUOT"):
    _FIXES[errno.EDQUOT] = "the disk quota is exceeded; free some space or choose another folder"


class WriteError(FileError):
    """``path`` cannot be written; ``strerror`` is the system's reason (``reason`` adds the fix)."""

    def __init__(self, path, strerror: str, fix: str):
        super().__init__(path, f"cannot write ({strerror}); {fix}")
        self.strerror = strerror


def write_error(path, error: OSError) -> WriteError:
    """The one-line UserError for an OSError met while writing ``path``."""
    return WriteError(path, error.strerror or str(error), _FIXES.get(error.errno, "choose another folder"))


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def _lock(fd: int) -> None:
    if fcntl is not None:
        fcntl.flock(fd, fcntl.LOCK_EX)


def _locked_temp(path: Path) -> tuple[int, str]:
    """A new temp file next to ``path``, created and locked; retried if a cleaner removed it before the lock."""
    while True:
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
        _lock(fd)
        if os.fstat(fd).st_nlink > 0:  # still linked: no cleaner took it in the instant before the lock
            return fd, tmp
        os.close(fd)


def refuse_directory(path, example: str = "out.png") -> None:
    """A UserError if ``path`` is an existing folder (an output file was expected)."""
    path = Path(path)
    if path.is_dir():
        raise UserError(f"{path}: is a directory; give a file name, e.g. {path / example}")


@contextlib.contextmanager
def atomic_open(path):
    """Open a temp file ``.NAME.*.tmp`` next to ``path``; on success it replaces ``path`` (one rename), on any
    error it is removed. A process killed mid-write can leave only that hidden temp file, never a partial
    ``path``; ``remove_stale_temps`` clears such leftovers."""
    path = Path(path)
    refuse_directory(path)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = _locked_temp(path)
    except OSError as error:
        raise write_error(path, error) from None
    f = os.fdopen(fd, "wb")
    try:
        try:
            yield f
            f.flush()
            os.fsync(f.fileno())
            os.chmod(tmp, 0o666 & ~_umask())  # mkstemp makes 0600 files; outputs get the usual mode
            if fcntl is None:
                f.close()  # Windows renames no open file
            os.replace(tmp, path)  # on POSIX still locked: a cleaner never takes a temp about to be renamed
        except OSError as error:
            if error.errno in _FIXES:
                raise write_error(path, error) from None
            raise
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise
    finally:
        with contextlib.suppress(OSError):
            f.close()


def write_bytes(path, data: bytes) -> None:
    """``data`` to ``path`` atomically."""
    with atomic_open(path) as f:
        f.write(data)


def _remove_if_abandoned(tmp: Path) -> bool:
    """Remove ``tmp`` if no live writer holds it (POSIX: we can take its lock, and unlink while we hold it;
    elsewhere: it is a day old). Returns whether it was removed."""
    if fcntl is None:
        try:
            if time.time() - tmp.stat().st_mtime > UNLOCKED_TEMP_AGE:
                tmp.unlink()
                return True
        except OSError:
            pass
        return False
    try:
        fd = os.open(tmp, os.O_RDONLY)
    except OSError:
        return False  # gone already (renamed into place, or removed)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)  # fails while a live writer holds it
        tmp.unlink()
        return True
    except OSError:
        return False
    finally:
        os.close(fd)


def remove_stale_temps(path) -> int:
    """Remove temp files of ``path`` that killed writers left behind; temps of live writers (other processes or
    threads writing ``path`` now) stay. Returns how many were removed."""
    path = Path(path)
    return sum(_remove_if_abandoned(tmp) for tmp in path.parent.glob(f".{glob.escape(path.name)}.*.tmp")
               if _is_temp(tmp, path.name))


def remove_abandoned_temps(folder) -> int:
    """``remove_stale_temps`` for every output in ``folder`` (not its subfolders): the temps no live writer holds.
    Returns how many were removed."""
    return sum(_remove_if_abandoned(tmp) for tmp in Path(folder).glob(".*.tmp") if _is_temp(tmp))


def _is_temp(path: Path, target: str | None = None) -> bool:
    """Whether ``path`` is named as ``atomic_open``'s temp (of ``target``, when given) and is a plain file."""
    match = TEMP_NAME.fullmatch(path.name)
    return bool(match) and (target is None or match["target"] == target) and path.is_file() and not path.is_symlink()


def output_dir(path, option: str = "") -> Path:
    """Make sure ``path`` is a folder this process can write to, creating it (and its missing parents); a one-line
    UserError naming ``option`` and the path otherwise: an empty path, an existing entry that is not a folder (a
    file, a dangling link), or a folder that cannot be created or written, in which case the folders made for it
    are removed again."""
    text = os.fspath(path)
    shown = text if text.strip() else repr(text)
    what = f"{option} {shown}" if option else shown
    if not text.strip():
        raise UserError(f"{what}: empty; give a folder path")
    path = Path(text)
    if os.path.lexists(path) and not path.is_dir():
        raise UserError(f"{what}: exists and is not a folder; give a folder path")
    created: list[Path] = []
    try:
        for folder in _missing_folders(path):
            folder.mkdir()
            created.append(folder)
        fd, probe = tempfile.mkstemp(prefix=".write-test.", suffix=".tmp", dir=path)
        os.close(fd)
        os.unlink(probe)
    except OSError as error:
        for folder in reversed(created):
            with contextlib.suppress(OSError):
                folder.rmdir()
        raise UserError(f"{what}: cannot write there ({error.strerror or error}); "
                        f"{_FIXES.get(error.errno, 'choose another folder')}") from None
    return path


def _missing_folders(path: Path) -> list[Path]:
    """``path`` and those of its parents that do not exist, outermost first."""
    missing = []
    while not os.path.lexists(path) and path.parent != path:
        missing.append(path)
        path = path.parent
    return missing[::-1]
