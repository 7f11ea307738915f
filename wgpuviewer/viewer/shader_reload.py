"""Shader hot reload for the viewer: watch the WGSL files, rebuild the renderer's cached pipelines on change.

A compile error leaves the last working pipeline in use and is reported as ``file:line:column: message`` in the
file that was edited (the composer's line map, ``wgpuviewer.core.wgsl.Module.locate``), for the HUD.
"""

from __future__ import annotations

import contextlib
from pathlib import Path

from wgpuviewer.core.wgsl import wgsl_dir


class ShaderReloader:
    """Polls the mtimes of the ``*.wgsl`` files under ``directory`` and rebuilds ``renderer``'s pipelines."""

    def __init__(self, renderer, directory: Path | None = None, interval: float = 0.5):
        self.renderer = renderer
        self.directory = directory if directory is not None else wgsl_dir()
        self.interval = interval
        self.errors: list[str] = []
        self._next_check = 0.0
        self._mtimes = self._scan()

    def _scan(self) -> dict[str, float]:
        if self.directory is None:
            return {}
        out = {}
        for path in self.directory.rglob("*.wgsl"):
            with contextlib.suppress(OSError):
                out[path.relative_to(self.directory).as_posix()] = path.stat().st_mtime_ns
        return out

    def poll(self, now: float) -> list[str]:
        """Check for edits at most every ``interval`` seconds; returns the changed file names."""
        if now < self._next_check or self.directory is None:
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
