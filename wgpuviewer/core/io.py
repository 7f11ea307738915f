"""Atomic file writes: every output of the project (renders, maps, reports, settings, caches) goes through
``atomic_open``, so a reader never sees a partial file, even after ``kill -9`` or a full disk. ``write_csv`` writes
the tables of results (benchmark, studies) that way."""

from __future__ import annotations

import contextlib
import csv
import glob
import io
import os
import tempfile
from pathlib import Path

from .errors import UserError


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


@contextlib.contextmanager
def atomic_open(path):
    """Open a temp file ``.NAME.*.tmp`` next to ``path``; on success it replaces ``path`` (one rename), on any
    error it is removed. A process killed mid-write can leave only that hidden temp file, never a partial
    ``path``; ``remove_stale_temps`` clears such leftovers."""
    path = Path(path)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    except OSError as error:
        raise UserError(f"{path}: cannot write here ({error.strerror or error}); choose another folder") from None
    try:
        with os.fdopen(fd, "wb") as f:
            yield f
            f.flush()
            os.fsync(f.fileno())
        os.chmod(tmp, 0o666 & ~_umask())  # mkstemp makes 0600 files; outputs get the usual mode
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise


def write_bytes(path, data: bytes) -> None:
    """``data`` to ``path`` atomically."""
    with atomic_open(path) as f:
        f.write(data)


def remove_stale_temps(path) -> None:
    """Remove temp files a killed writer of ``path`` left behind (only call for outputs this process owns)."""
    path = Path(path)
    for tmp in path.parent.glob(f".{glob.escape(path.name)}.*.tmp"):
        with contextlib.suppress(OSError):
            tmp.unlink()


def csv_cell(value) -> str:
    """A CSV cell: floats with 6 significant digits, everything else as text."""
    return f"{value:.6g}" if isinstance(value, float) else str(value)


def write_csv(path, columns, rows) -> None:
    """``rows`` (dicts with at least ``columns``) as a CSV file with a header, atomically."""
    text = io.StringIO(newline="")
    writer = csv.DictWriter(text, fieldnames=list(columns), lineterminator="\n", extrasaction="ignore")
    writer.writeheader()
    for row in rows:
        writer.writerow({k: csv_cell(row[k]) for k in columns})
    write_bytes(path, text.getvalue().encode("utf-8"))
