"""The record ``maptools batch`` writes next to each map it makes (``NAME.json`` beside ``NAME``): what the map was
built from and how. maptools writes it and reads it back (its up-to-date check, inputs that are its own outputs);
scenes read it to check a map they name against the material's height file (``[materials.X.maps]``), the renderer
to check the map's kind, options and bytes before it serves the file, and material-folder scans to leave recorded
maps out (a batch output next to the textures is not one of them).
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import asdict, dataclass
from pathlib import Path

from .errors import FileError
from .io import atomic_open

SUFFIX = ".json"
#: How every maptools version string starts (``maptools.VERSION``): a JSON file next to a map that does not say
#: so is someone else's, not a record.
VERSION_PREFIX = "maptools-"


@dataclass(frozen=True)
class MapRecord:
    """What one map file was built from: the height file (its path as the batch was given it, the sha256 of its
    bytes, the channel read as height), the kind and its resolved options, the maptools version and the hash of the
    kind's kernels, the batch job's key (its up-to-date check) and the sha256 of the map file as written."""

    key: str
    kind: str
    options: dict
    version: str
    kernels: str
    input: str
    input_sha256: str
    channel: str
    output_sha256: str


def record_path(map_path) -> Path:
    map_path = Path(map_path)
    return map_path.with_name(map_path.name + SUFFIX)


def file_sha256(path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as f:
        while chunk := f.read(1 << 20):
            h.update(chunk)
    return h.hexdigest()


def write_record(map_path, record: MapRecord) -> None:
    """The record of the map at ``map_path``, written atomically after the map (a record never names a map that
    is not complete)."""
    with atomic_open(record_path(map_path)) as f:
        f.write(json.dumps(asdict(record), sort_keys=True).encode())


def read_record(map_path) -> MapRecord:
    """The record of the map at ``map_path``; FileError (naming the record file) when there is none, it cannot be
    read, it is not maptools', or it lacks a field (written by an older maptools)."""
    path = record_path(map_path)
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise FileError(path, "not found; name a map written by maptools batch, which writes this record of the "
                              "height it was built from next to the map") from None
    except (OSError, UnicodeDecodeError, ValueError) as error:
        raise FileError(path, f"cannot be read as a maptools record ({error}); run maptools batch again") from None
    if not (isinstance(data, dict) and str(data.get("version", "")).startswith(VERSION_PREFIX)):
        raise FileError(path, "is not a record written by maptools batch")
    fields = MapRecord.__dataclass_fields__
    missing = sorted(set(fields) - set(data))
    if missing:
        raise FileError(path, f"written by an older maptools batch (no {', '.join(missing)}); run the batch again "
                              "with --force")
    wrong = [name for name in fields if not isinstance(data[name], dict if name == "options" else str)]
    if wrong:
        raise FileError(path, f"damaged: {', '.join(wrong)} of the wrong type; run maptools batch again with --force")
    return MapRecord(**{name: data[name] for name in fields})


def is_recorded(path) -> bool:
    """Whether ``path`` is a map maptools wrote: a maptools record lies next to it (an outdated record counts)."""
    try:
        data = json.loads(record_path(path).read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, ValueError):
        return False
    return isinstance(data, dict) and str(data.get("version", "")).startswith(VERSION_PREFIX)
