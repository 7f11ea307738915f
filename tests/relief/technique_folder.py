"""A throw-away technique folder for tests: written under a temporary directory that joins the registry's search
path (``wgpuviewer.techniques.__path__``), so discovery finds it like a shipped one, and leaves it again."""

from __future__ import annotations

import contextlib
import sys
from collections.abc import Iterator
from pathlib import Path

import wgpuviewer.techniques as registry
from wgpuviewer.techniques import TECHNIQUES, Technique


@contextlib.contextmanager
def technique_folder(root: Path, name: str, init: str, wgsl: str = "") -> Iterator[Technique]:
    """Technique ``name`` from ``root/name/__init__.py`` (source ``init``, defining TECHNIQUE) and, given ``wgsl``,
    ``root/name/name.wgsl``; registered while the block runs."""
    folder = root / name
    folder.mkdir(parents=True)
    (folder / "__init__.py").write_text(init)
    if wgsl:
        (folder / f"{name}.wgsl").write_text(wgsl)
    registry.__path__.append(str(root))
    try:
        yield TECHNIQUES[name]
    finally:
        registry.__path__.remove(str(root))
        sys.modules.pop(f"{registry.__name__}.{name}", None)
