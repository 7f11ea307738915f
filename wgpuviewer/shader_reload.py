"""Shader hot reload for the viewer: watch the WGSL files, rebuild cached pipelines on change.

A compile error leaves the last working pipeline in use and is reported as ``file:line:column:
message`` in the file that was edited (not in the composed module), for the HUD.
"""

from __future__ import annotations

import re
from pathlib import Path

import wgpu

from . import shaders
from .techniques import get_technique

_LOCATION = re.compile(r"wgsl:(\d+):(\d+)")


def wgsl_dir() -> Path | None:
    """The directory of the WGSL files when they are plain files (checkout or installed package)."""
    try:
        path = Path(str(shaders.WGSL))
    except TypeError:
        return None
    return path if path.is_dir() else None


def locate(message: str, source: str, names: list[str]) -> str:
    """``message`` (naga's, in composed-source lines) as 'FILE:LINE:COL: reason'."""
    reason = _reason(message)
    match = _LOCATION.search(message)
    if not match:
        return reason
    line, col = int(match.group(1)), int(match.group(2))
    for name in names:
        text = shaders.read_wgsl(name)
        start = source.find(text) if text else -1
        if start < 0:
            continue
        first = source.count("\n", 0, start) + 1
        last = first + text.count("\n")
        if first <= line <= last:
            return f"{name}:{line - first + 1}:{col}: {reason}"
    return f"<generated>:{line}:{col}: {reason}"


def _reason(message: str) -> str:
    for text in message.splitlines():
        text = text.strip()
        if "error" in text.lower() and not text.lower().startswith("validation error"):
            return re.sub(r"^Shader '[^']*' ", "", text)
    return message.strip().splitlines()[0] if message.strip() else "unknown error"


class ShaderReloader:
    """Polls the mtimes of ``*.wgsl`` in ``directory`` and rebuilds ``renderer``'s pipelines."""

    def __init__(self, renderer, directory: Path | None = None, interval: float = 0.5):
        self.renderer = renderer
        self.directory = directory if directory is not None else wgsl_dir()
        self.interval = interval
        self.errors: list[str] = []
        self.reloaded = 0  # successful rebuilds, for the HUD
        self._next_check = 0.0
        self._mtimes = self._scan()

    def _scan(self) -> dict[str, float]:
        if self.directory is None:
            return {}
        out = {}
        for path in self.directory.glob("*.wgsl"):
            try:
                out[path.name] = path.stat().st_mtime_ns
            except OSError:
                pass
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
            self.reload(changed)
        return changed

    def reload(self, changed=()) -> list[str]:
        """Rebuild every cached pipeline; on failure keep the old one. Returns (and keeps) the errors."""
        names = sorted(self._mtimes) if self._mtimes else []
        for name in changed:
            if name not in names:
                names.append(name)
        errors = []
        pipelines = self.renderer._pipelines
        for key in list(pipelines):
            technique = get_technique(key[0])
            old = pipelines.pop(key)
            try:
                self.renderer.pipeline(technique, key[1])
                self.reloaded += 1
            except wgpu.GPUError as error:
                pipelines[key] = old
                try:
                    source = shaders.compose(technique, "render")
                except OSError as read_error:
                    errors.append(f"{read_error}")
                    continue
                located = locate(str(error), source, names or [technique.wgsl_file])
                if located not in errors:
                    errors.append(located)
        self.errors = errors
        return errors
