"""Shader hot reload for the viewer: watch the WGSL files (``wgsl/`` and the technique folders), rebuild the
renderer's cached pipelines on change.

A compile error leaves the last working pipeline in use and is reported as ``file:line:column: message`` in the
file that was edited (the composer's line map, ``wgpuviewer.core.wgsl.Module.locate``), for the HUD.
"""

from __future__ import annotations

import contextlib
from pathlib import Path

from wgpuviewer import techniques
from wgpuviewer.core.wgsl import wgsl_dir


class ShaderReloader:
    """Polls the mtimes of the ``*.wgsl`` files under ``directories`` (default: ``wgsl/`` and the technique
    folders' package) and rebuilds ``renderer``'s pipelines."""

    def __init__(self, renderer, directories: tuple[Path, ...] | None = None, interval: float = 0.5):
        self.renderer = renderer
        if directories is None:
            shared = wgsl_dir()  # None where the package's files are not plain files: nothing to watch there
            directories = (*((shared,) if shared is not None else ()), *map(Path, techniques.__path__))
        self.directories = directories
        self.interval = interval
        self.errors: list[str] = []
        self._next_check = 0.0
        self._mtimes = self._scan()

    def _scan(self) -> dict[str, float]:
        """mtime of every file, by its path relative to its directory (e.g. common/trace.wgsl, pom/pom.wgsl)."""
        out = {}
        for directory in self.directories:
            for path in directory.rglob("*.wgsl"):
                with contextlib.suppress(OSError):
                    out[path.relative_to(directory).as_posix()] = path.stat().st_mtime_ns
        return out

    def poll(self, now: float) -> list[str]:
        """Check for edits at most every ``interval`` seconds; returns the changed file names."""
        if now < self._next_check or not self.directories:
            return []
        self._next_check = now + self.interval
        mtimes = self._scan()
        changed = sorted(n for n in mtimes.keys() | self._mtimes.keys() if mtimes.get(n) != self._mtimes.get(n))
        self._mtimes = mtimes
        if changed:
            self.reload()
        return changed

    def reload(self) -> list[str]:
        """Rebuild every cached pipeline; on failure keep the old one. Returns (and keeps) the errors."""
        errors = []
        for _technique, located in self.renderer.rebuild_pipelines():
            if located not in errors:
                errors.append(located)
        self.errors = errors
        return errors
