"""The one WGSL composer, for technique shaders and map kernels alike.

A WGSL file names what it needs with include lines of its own, resolved against the ``wgsl/`` folder (which ships
as the package data ``wgpuviewer.wgsl``)::

    // #include "common/cell.wgsl"

``compose`` takes the files and generated pieces a module is made of, adds every file they include (each file
once, whatever includes it, after what it includes: module-scope WGSL declarations may come in any order, so this
is only for reading), and keeps a line map, so that a compile error in the composed module is reported at the
original ``file:line:column`` (``Module.locate``).
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from importlib.resources import files
from pathlib import Path

_INCLUDE = re.compile(r'^\s*//\s*#include\s+"([^"]+)"\s*$')
_LOCATION = re.compile(r"wgsl:(\d+):(\d+)")


def wgsl_root():
    """The ``wgsl/`` folder (a Traversable; a plain directory in a checkout or an installed package)."""
    return files("wgpuviewer.wgsl")


def wgsl_dir() -> Path | None:
    """``wgsl/`` as a filesystem path when its files are plain files (for the viewer's hot reload), else None."""
    try:
        path = Path(str(wgsl_root()))
    except TypeError:
        return None
    return path if path.is_dir() else None


def read_wgsl(name: str) -> str:
    """Text of a WGSL file: ``name`` relative to ``wgsl/`` (e.g. "common/trace.wgsl"), or an absolute path (e.g. a
    technique folder's file)."""
    path = Path(name)
    if path.is_absolute():
        return path.read_text(encoding="utf-8")
    node = wgsl_root()
    for part in name.split("/"):
        node = node / part
    return node.read_text(encoding="utf-8")


@dataclass(frozen=True)
class Generated:
    """A piece of WGSL made in Python (e.g. the ``TraceParams`` struct from the technique registry)."""

    name: str  # shown in error locations, e.g. "<generated: trace params>"
    text: str


@dataclass(frozen=True)
class Module:
    """A composed shader module: its ``code`` and, per line of it, the (file, line) it came from."""

    code: str
    lines: tuple[tuple[str, int], ...]
    files: tuple[str, ...]  # the WGSL files it was made of, in order

    def origin(self, line: int) -> tuple[str, int]:
        """(file, line in that file) of line ``line`` (1-based) of the composed code."""
        if 1 <= line <= len(self.lines):
            return self.lines[line - 1]
        return "<composed>", line

    def locate(self, message: str) -> str:
        """A compiler message about the composed code as 'FILE:LINE:COL: reason' in the original file."""
        reason = _reason(message)
        match = _LOCATION.search(message)
        if not match:
            return reason
        name, line = self.origin(int(match.group(1)))
        return f"{name}:{line}:{match.group(2)}: {reason}"


def _reason(message: str) -> str:
    for text in message.splitlines():
        text = text.strip()
        if "error" in text.lower() and not text.lower().startswith("validation error"):
            return re.sub(r"^Shader '[^']*' ", "", text)
    return message.strip().splitlines()[0] if message.strip() else "unknown error"


def includes(text: str) -> list[str]:
    """The files a WGSL text includes, in order."""
    return [m.group(1) for m in map(_INCLUDE.match, text.splitlines()) if m]


def compose(*parts: str | Generated) -> Module:
    """One module from WGSL file names (relative to ``wgsl/`` or absolute) and generated pieces, with every
    included file added once."""
    order: list[tuple[str, str]] = []  # (name, text) in output order
    seen: set[str] = set()

    def add(name: str, visiting: tuple[str, ...] = ()) -> None:
        if name in seen:
            return
        if name in visiting:
            raise ValueError(f"WGSL include cycle: {' -> '.join((*visiting, name))}")
        text = read_wgsl(name)
        for child in includes(text):
            add(child, (*visiting, name))
        seen.add(name)
        order.append((name, text))

    for part in parts:
        if isinstance(part, Generated):
            order.append((part.name, part.text))
        else:
            add(part)
    code_lines: list[str] = []
    origins: list[tuple[str, int]] = []
    for name, text in order:
        for number, line in enumerate(text.splitlines(), 1):
            if _INCLUDE.match(line):
                continue
            code_lines.append(line)
            origins.append((name, number))
    return Module("\n".join(code_lines) + "\n", tuple(origins),
                  tuple(name for name, _ in order if not name.startswith("<")))
