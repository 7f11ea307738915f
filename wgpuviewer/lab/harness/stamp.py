"""The stamp of a results folder (``stamp.json``): what it measured (the command line, the adapter, the date, the
seconds) and the fingerprint of the code its numbers depend on, so that ``wgpuviewer results`` can tell a folder
measured on today's code (fresh) from one measured on older code (stale) and name what changed.

The fingerprint is a set of named parts, each the sha256 (first 16 hex digits) of the files it is made of, as
(path, content) pairs in path order; a file that is absent counts as absent, so a part that moved or vanished
differs too:

- ``technique NAME``: the technique's folder (``wgpuviewer/techniques/NAME/``: its entry and its WGSL), every WGSL
  file its WGSL includes (the composed search code, resolved against ``wgsl/``) and ``techniques/shared.py``;
- ``map KIND``: the folder of every map kind the technique's entry names (``maptools/kinds/KIND/``), with the WGSL
  it includes and the ``maptools/...wgsl`` kernels its drivers name;
- ``filter NAME``: ``wgsl/filters/NAME.wgsl`` with what it includes, for the filters the results name;
- ``entry NAME``: the entry points a measurement can run, with what they include: the probe's, the renderer's and
  the filter, gradient and shadow probes' (``ENTRIES``; the viewer's own passes are left out);
- ``code PACKAGE``: the Python of the measuring command's own package (``wgpuviewer/lab/bench``, a study's folder),
  but its ``docs.py`` (which only formats the results into pages).

The techniques and filters of a folder are the values of the ``technique`` and ``filter`` columns of its CSV files
(every technique when no CSV has a ``technique`` column). Left out on purpose: the product's shared Python runtime
(``core``, ``relief``'s passes, the float64 reference), which the tests hold to their references; a change there
that moves a measured number is not seen by the stamp.

``Files`` reads a checkout on disk; ``wgpuviewer.lab.results`` also reads one commit of git with the same parts.
May import: ``wgpuviewer.core`` only.
"""

from __future__ import annotations

import csv
import datetime
import hashlib
import json
import re
from collections.abc import Iterable
from pathlib import Path
from typing import Protocol

from wgpuviewer.core.io import write_bytes
from wgpuviewer.core.wgsl import includes

STAMP = "stamp.json"
DEFINITION = 2  # the fingerprint's definition (this docstring); a stamp of another definition is stale
CHECKOUT = Path(__file__).resolve().parents[3]
TECHNIQUES = "wgpuviewer/techniques"
KINDS = "maptools/kinds"
ENTRIES = ("probe", "render", "filter_probe", "gradient_probe", "shadow_probe")
_QUOTED = re.compile(r"[\"']([a-z_]+)[\"']")
_KERNEL = re.compile(r"maptools/[\w/]+\.wgsl")


class Source(Protocol):
    """Files of one version of the checkout, by path relative to its root (posix)."""

    def read(self, path: str) -> bytes | None:
        """The file's bytes, or None when there is no such file."""

    def listing(self, folder: str) -> list[str]:
        """Every file under ``folder`` (recursively), sorted; empty when there is no such folder."""


class Files:
    """The checkout on disk at ``root``."""

    def __init__(self, root: Path):
        self.root = Path(root)

    def read(self, path: str) -> bytes | None:
        file = self.root / path
        return file.read_bytes() if file.is_file() else None

    def listing(self, folder: str) -> list[str]:
        base = self.root / folder
        if not base.is_dir():
            return []
        return sorted(p.relative_to(self.root).as_posix() for p in base.rglob("*")
                      if p.is_file() and "__pycache__" not in p.parts)


def _sources(paths: Iterable[str]) -> list[str]:
    return [p for p in paths if p.endswith((".py", ".wgsl"))]


def _with_includes(source: Source, paths: Iterable[str]) -> set[str]:
    """``paths`` and every WGSL file they include, transitively (include names are relative to ``wgsl/``)."""
    found, todo = set(), list(paths)
    while todo:
        path = todo.pop()
        if path in found:
            continue
        found.add(path)
        data = source.read(path) if path.endswith(".wgsl") else None
        if data is not None:
            todo += [f"wgsl/{name}" for name in includes(data.decode("utf-8", "replace"))]
    return found


def _digest(source: Source, paths: Iterable[str]) -> str:
    h = hashlib.sha256()
    for path in sorted(set(paths)):
        data = source.read(path)
        h.update(f"{path}\0{'-' if data is None else len(data)}\0".encode())
        h.update(data or b"")
    return h.hexdigest()[:16]


def technique_names(source: Source) -> list[str]:
    return sorted({p.split("/")[2] for p in source.listing(TECHNIQUES)
                   if p.count("/") == 3 and p.endswith("/__init__.py")})


def map_kinds(source: Source, technique: str) -> list[str]:
    """The map kinds the technique's entry names (quoted names that are kind folders)."""
    kinds = {p.split("/")[2] for p in source.listing(KINDS) if p.count("/") >= 3}
    entry = (source.read(f"{TECHNIQUES}/{technique}/__init__.py") or b"").decode("utf-8", "replace")
    return sorted(kinds & set(_QUOTED.findall(entry)))


def part_files(source: Source, part: str) -> set[str]:
    """The files of one named part (see the module's docstring)."""
    kind, _, name = part.partition(" ")
    if kind == "technique":
        own = _sources(source.listing(f"{TECHNIQUES}/{name}"))
        return _with_includes(source, [*own, f"{TECHNIQUES}/shared.py"])
    if kind == "map":
        own = _sources(source.listing(f"{KINDS}/{name}"))
        kernels = {k for p in own if p.endswith(".py") for k in _KERNEL.findall(source.read(p).decode("utf-8", "replace"))}
        return _with_includes(source, [*own, *kernels])
    if kind == "filter":
        return _with_includes(source, [f"wgsl/filters/{name}.wgsl"])
    if kind == "entry":
        return _with_includes(source, [f"wgsl/entry/{name}.wgsl"])
    if kind == "code":  # its docs.py only formats the results into pages: not measuring code
        return {p for p in _sources(source.listing(name)) if not p.endswith("/docs.py")}
    raise ValueError(f"unknown fingerprint part {part!r}")


def parts_for(source: Source, techniques: Iterable[str] | None, filters: Iterable[str], package: str) -> list[str]:
    """The part names a folder depends on: its techniques (None: all) with their maps, its filters, the entry
    points, its measuring package."""
    known = technique_names(source)
    chosen = known if techniques is None else sorted(set(techniques) & set(known))
    kinds = sorted({k for t in chosen for k in map_kinds(source, t)})
    return ([f"technique {t}" for t in chosen] + [f"map {k}" for k in kinds] +
            [f"filter {f}" for f in sorted(set(filters))] + [f"entry {e}" for e in ENTRIES] + [f"code {package}"])


def fingerprint(source: Source, parts: Iterable[str]) -> dict[str, str]:
    return {part: _digest(source, part_files(source, part)) for part in parts}


def used_names(folder: Path) -> tuple[set[str] | None, set[str]]:
    """(techniques, filters) named in the ``technique`` and ``filter`` columns of the folder's CSV files;
    techniques None when no CSV has a ``technique`` column."""
    techniques, filters, seen = set(), set(), False
    for path in sorted(Path(folder).glob("*.csv")):
        with open(path, newline="", encoding="utf-8") as f:
            for row in csv.DictReader(f):
                if "technique" in row:
                    seen = True
                    techniques.add(row["technique"])
                if row.get("filter"):
                    filters.add(row["filter"])
    return (techniques if seen else None), filters


def package_of(module_file: str, root: Path = CHECKOUT) -> str:
    """The measuring package of a module file: its folder, relative to ``root`` (absolute when outside it)."""
    folder = Path(module_file).resolve().parent
    return folder.relative_to(Path(root).resolve()).as_posix() if folder.is_relative_to(Path(root).resolve()) \
        else folder.as_posix()


def everything(source: Source, package: str) -> dict[str, str]:
    """Every part a run in ``package`` could depend on, hashed now (before the run: the code it loaded)."""
    filters = [Path(p).stem for p in source.listing("wgsl/filters") if p.endswith(".wgsl")]
    return fingerprint(source, parts_for(source, None, filters, package))


_ADAPTER = re.compile(r"^- adapter: \*\*(.+?)\*\*", re.MULTILINE)


def adapter_of(folder: Path) -> str:
    """The adapter a folder's report.md header names (``header.Header``), else "unknown"."""
    report = Path(folder) / "report.md"
    match = _ADAPTER.search(report.read_text(encoding="utf-8")) if report.is_file() else None
    return match[1] if match else "unknown (no report header)"


def stamp(folder: Path, command: str, started: datetime.datetime, seconds: float, before: dict[str, str],
          package: str) -> dict:
    """The stamp of a run that just wrote ``folder``: ``before`` (``everything`` at its start) cut to the parts
    its results use."""
    techniques, filters = used_names(folder)
    used = parts_for(Files(CHECKOUT), techniques, filters, package)
    return {"definition": DEFINITION, "source": "run", "command": command, "adapter": adapter_of(folder),
            "date": started.strftime("%Y-%m-%dT%H:%M:%SZ"), "seconds": round(seconds, 1),
            "parts": {p: before.get(p, "absent at the start") for p in used}}


def write(folder: Path, record: dict) -> None:
    write_bytes(Path(folder) / STAMP, (json.dumps(record, indent=2, ensure_ascii=False) + "\n").encode())


def read(folder: Path) -> dict | None:
    """The folder's stamp, or None when it has none."""
    path = Path(folder) / STAMP
    return json.loads(path.read_text(encoding="utf-8")) if path.is_file() else None
