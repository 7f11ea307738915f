"""Viewer settings persisted between sessions in the platform's user configuration directory.

``settings.toml`` lives in ``$WGPUVIEWER_CONFIG_DIR`` when set (tests), else
``%APPDATA%\\wgpuviewer`` (Windows), ``~/Library/Application Support/wgpuviewer`` (macOS) or
``$XDG_CONFIG_HOME/wgpuviewer`` (default ``~/.config/wgpuviewer``, Linux and others).
A missing file gives the defaults silently; a corrupt or outdated file, or a bad value, gives the
defaults (for that value) and a warning, never a crash. Writes are atomic; a folder that cannot be written is a
warning at the end of a session (``save_session``).
"""

from __future__ import annotations

import logging
import math
import os
import sys
import tomllib
from dataclasses import asdict, dataclass, fields, replace
from pathlib import Path

from wgpuviewer.core import env
from wgpuviewer.core.errors import UserError

from .render_scale import CHOICES

CONFIG_ENV = env.CONFIG_DIR.name
FILE_NAME = "settings.toml"
#: Bumped when the meaning of a key changes; a file with another version is replaced by defaults.
VERSION = 1

log = logging.getLogger("wgpuviewer.settings")


@dataclass(frozen=True)
class Settings:
    width: int = 1280  # window size in logical pixels
    height: int = 720
    fullscreen: bool = False
    vsync: bool = True
    camera_mode: str = "fly"  # "fly" or "orbit"
    move_speed: float = 1.5  # scene units per second (fly camera)
    look_sensitivity: float = 0.005  # radians per pixel dragged
    zoom_sensitivity: float = 0.1  # orbit distance factor per wheel step
    show_hud: bool = True
    show_stats: bool = True
    last_scene: str = ""  # path of the last scene opened ("" = the built-in default scene)
    last_technique: str = ""
    render_scale: str = "auto"  # render_scale.CHOICES: 'auto' (a software adapter chooses) or the scene's fraction


#: (min, max) for numbers, allowed values for strings.
LIMITS = {
    "width": (64, 16384),
    "height": (64, 16384),
    "move_speed": (0.01, 100.0),
    "look_sensitivity": (0.0001, 0.1),
    "zoom_sensitivity": (0.01, 0.9),
    "camera_mode": ("fly", "orbit"),
    "render_scale": CHOICES,
}


def config_dir() -> Path:
    override = env.CONFIG_DIR.value()
    if override:
        return override
    if sys.platform.startswith("win"):
        base = os.environ.get("APPDATA")
        return Path(base) / "wgpuviewer" if base else Path.home() / "AppData" / "Roaming" / "wgpuviewer"
    if sys.platform == "darwin":
        return Path.home() / "Library" / "Application Support" / "wgpuviewer"
    base = os.environ.get("XDG_CONFIG_HOME")
    return (Path(base) if base and os.path.isabs(base) else Path.home() / ".config") / "wgpuviewer"


def settings_path() -> Path:
    return config_dir() / FILE_NAME


def _check(name: str, value, default):
    """The value if it has the right type and range, else raise ValueError with the reason."""
    kind = type(default)
    if kind is bool:
        ok = isinstance(value, bool)
    elif kind is int:
        ok = isinstance(value, int) and not isinstance(value, bool)
    elif kind is float:
        ok = isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)
    else:
        ok = isinstance(value, str)
    if not ok:
        raise ValueError(f"expected {kind.__name__}")
    limits = LIMITS.get(name)
    if limits and isinstance(limits[0], str):
        if value not in limits:
            raise ValueError(f"expected one of {', '.join(limits)}")
    elif limits and not (limits[0] <= value <= limits[1]):
        raise ValueError(f"out of range {limits[0]:g} to {limits[1]:g}")
    return kind(value)


def load_settings(path: Path | None = None) -> tuple[Settings, list[str]]:
    """Settings from ``path`` (default: settings_path()) and the warnings met while reading it."""
    path = Path(path) if path else settings_path()
    warnings: list[str] = []
    defaults = Settings()
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        return defaults, warnings
    except (OSError, UnicodeDecodeError) as error:
        return defaults, _warn(warnings, f"{path}: unreadable ({error}); using default settings")
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as error:
        return defaults, _warn(warnings, f"{path}: corrupt ({error}); using default settings")
    if data.get("version") != VERSION:
        return defaults, _warn(
            warnings, f"{path}: settings version {data.get('version')!r}, expected {VERSION}; using default settings"
        )
    values = {}
    known = {f.name: f.default for f in fields(Settings)}
    for name, value in data.items():
        if name == "version":
            continue
        if name not in known:
            _warn(warnings, f"{path}: unknown setting {name!r} ignored")
            continue
        try:
            values[name] = _check(name, value, known[name])
        except ValueError as reason:
            _warn(warnings, f"{path}: {name} = {value!r}: {reason}; using the default {known[name]!r}")
    return replace(defaults, **values), warnings


def _warn(warnings: list[str], message: str) -> list[str]:
    log.warning(message)
    warnings.append(message)
    return warnings


def _toml_value(value) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (int, float)):
        return repr(value)
    escaped = "".join(
        {"\\": "\\\\", '"': '\\"', "\n": "\\n", "\t": "\\t", "\r": "\\r"}.get(c, c)
        if c >= " " or c in "\n\t\r" else f"\\u{ord(c):04x}"
        for c in str(value)
    )
    return f'"{escaped}"'


def dumps(settings: Settings) -> str:
    lines = ["# wgpuviewer settings (written by the viewer; delete this file to get the defaults)",
             f"version = {VERSION}"]
    lines += [f"{name} = {_toml_value(value)}" for name, value in asdict(settings).items()]
    return "\n".join(lines) + "\n"


def save_settings(settings: Settings, path: Path | None = None) -> Path:
    """Write atomically (a temporary file moved into place): a crash never leaves half a file."""
    from wgpuviewer.core.io import atomic_open

    path = Path(path) if path else settings_path()
    with atomic_open(path) as f:
        f.write(dumps(settings).encode("utf-8"))
    return path


def save_session(settings: Settings) -> None:
    """Save the settings at the end of a session; a folder that cannot be written is a warning naming it and
    the variable that moves it, never a failed session."""
    try:
        path = save_settings(settings)
        print(f"settings saved to {path}", file=sys.stderr)
    except (OSError, UserError) as error:
        reason = getattr(error, "strerror", None) or str(error)
        print(f"wgpuviewer: warning: settings not saved: {settings_path()} cannot be written ({reason}); "
              f"set {CONFIG_ENV} to a writable folder", file=sys.stderr)
