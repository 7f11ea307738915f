"""The project's environment variables, each parsed in one place for every command and library call:

- ``WGPUVIEWER_BACKEND``: the wgpu backend when no ``--backend`` is given (auto, vulkan, metal, dx12, gl);
- ``WGPU_BACKEND_TYPE``: wgpu-py's variable for the same choice, in its names (Vulkan, Metal, D3D12, OpenGL,
  OpenGLES, Undefined for auto), used when ``WGPUVIEWER_BACKEND`` is unset; when both are set ours wins, and a
  one-line notice says so where they disagree (a bad ``WGPU_BACKEND_TYPE`` is then ignored, not refused);
- ``WGPUVIEWER_CACHE_DIR``: the map cache folder (default ``~/.cache/wgpuviewer/maps``);
- ``WGPUVIEWER_CACHE_MAX``: the map cache's size cap (500M, 2G, 1.5T, bytes; 0 turns the cap off; default 2G);
- ``WGPUVIEWER_CONFIG_DIR``: the viewer's settings folder (default: the platform's config folder).

An empty value is the same as an unset one; ``~`` in a path is the home folder. A bad value is a ``UserError``
naming the variable, the value and the fix. Both CLIs check every variable before their command runs
(``core.commands.run_command``), so no command accepts a value another refuses, whether or not it reaches the code that
uses it. Variables of other systems (DISPLAY, WAYLAND_DISPLAY, XDG_*, APPDATA, OPENCV_*) are read where they are
used, as those systems define them.

Also what the GPU drivers read from the environment (``prepare_driver_environment``: a private
``$XDG_RUNTIME_DIR``), set by both CLIs and by the first adapter request of a library call.

Standard library only: ``core.commands`` imports this before any GPU driver loads.
"""

from __future__ import annotations

import logging
import os
import re
import stat
import tempfile
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from .errors import UserError

log = logging.getLogger("wgpuviewer.env")

_SIZE_UNITS = {"": 1, "K": 2**10, "M": 2**20, "G": 2**30, "T": 2**40}


def parse_bytes(text: str) -> int:
    """'500M', '2G', '1.5T', '2GiB', '123' (bytes), '0' -> bytes; ValueError with what is expected otherwise."""
    match = re.fullmatch(r"\s*(\d+(?:\.\d*)?)\s*([KMGT]?)(?:I?B)?\s*", text, re.IGNORECASE)
    if not match:
        raise ValueError("expected a size such as 500M, 2G or 0 (no cap)")
    size = float(match[1]) * _SIZE_UNITS[match[2].upper()]
    if 0 < size < 1:  # would round to 0, which means "no cap": not what was written
        raise ValueError("less than one byte; expected a size such as 500M, 2G or 0 (no cap)")
    return int(size)


def _choice(choices: tuple[str, ...]) -> Callable[[str], str]:
    def parse(text: str) -> str:
        name = text.strip().lower()
        if name not in choices:
            raise ValueError(f"expected one of {', '.join(choices)}")
        return name

    return parse


def _path(text: str) -> Path:
    return Path(text.strip()).expanduser()


#: (variable, value, ignored variable, its value) already noted: the notice prints once per process.
_NOTED: set[tuple[str, str, str, str]] = set()


@dataclass(frozen=True)
class Variable:
    """One environment variable: ``parse`` turns a set value into what it means (ValueError: what is expected);
    ``default`` is used when it is unset or empty, ``default_text`` says what that is in errors. ``fallback``:
    another system's variable for the same setting, whose value is used instead of the default while this one is
    unset; when both are set this one wins, with a one-line notice (a ``wgpuviewer.env`` warning, once) where
    the two disagree."""

    name: str
    parse: Callable[[str], Any]
    default: Any
    default_text: str
    fallback: Variable | None = None

    def raw(self) -> str | None:
        """The value as set, None when unset or empty."""
        text = os.environ.get(self.name)
        return text if text and text.strip() else None

    def value(self):
        """What the variable means now (read each call: tests and embedding programs change the environment)."""
        text = self.raw()
        if text is None:
            return self.default if self.fallback is None else self.fallback.value()
        value = self._parsed(text)
        if self.fallback is not None:
            self._note_ignored_fallback(text, value)
        return value

    def _parsed(self, text: str):
        try:
            return self.parse(text)
        except ValueError as error:
            raise UserError(f"${self.name} = {text!r}: {error}; set a valid value or unset it "
                            f"(default: {self.default_text})") from None

    def _note_ignored_fallback(self, text: str, value) -> None:
        other = self.fallback.raw()
        if other is None:
            return
        try:
            same = self.fallback._parsed(other) == value
        except UserError:  # ours wins: a value of theirs we could not use changes nothing
            same = False
        key = (self.name, text, self.fallback.name, other)
        if not same and key not in _NOTED:
            _NOTED.add(key)
            log.warning(f"${self.name} = {text!r} wins over ${self.fallback.name} = {other!r}; unset one of them "
                        "to silence this")


#: wgpu backend names (``core.gpu.BACKEND_CHOICES`` is the same tuple, checked by a test).
BACKEND_CHOICES = ("auto", "vulkan", "metal", "dx12", "gl")

#: wgpu-py's backend names (``WGPU_BACKEND_TYPE``, its ``BackendType`` enum) of the backends we run on, as ours.
WGPU_BACKEND_NAMES = {"Undefined": "auto", "Vulkan": "vulkan", "Metal": "metal", "D3D12": "dx12", "OpenGL": "gl",
                      "OpenGLES": "gl"}


def _wgpu_backend(text: str) -> str:
    """A ``WGPU_BACKEND_TYPE`` value (any case) as one of BACKEND_CHOICES."""
    for name, ours in WGPU_BACKEND_NAMES.items():
        if text.strip().lower() == name.lower():
            return ours
    raise ValueError(f"expected one of {', '.join(WGPU_BACKEND_NAMES)} (wgpu-py's names of the backends "
                     "wgpuviewer runs on)")


WGPU_BACKEND = Variable("WGPU_BACKEND_TYPE", _wgpu_backend, "auto", "auto")
BACKEND = Variable("WGPUVIEWER_BACKEND", _choice(BACKEND_CHOICES), "auto", f"${WGPU_BACKEND.name}, else auto",
                   fallback=WGPU_BACKEND)
CACHE_DIR = Variable("WGPUVIEWER_CACHE_DIR", _path, None, "~/.cache/wgpuviewer/maps")
CACHE_MAX = Variable("WGPUVIEWER_CACHE_MAX", parse_bytes, 2 * 2**30, "2G")
CONFIG_DIR = Variable("WGPUVIEWER_CONFIG_DIR", _path, None, "the platform's config folder")

#: The project's variables (a fallback is read through the variable it stands in for).
VARIABLES = (BACKEND, CACHE_DIR, CACHE_MAX, CONFIG_DIR)


def check_environment() -> None:
    """Parse every variable (and the fallback of one that is unset): the first bad one is a UserError."""
    for variable in VARIABLES:
        variable.value()


def _runtime_dir_ok(path: str | None) -> bool:
    """What Mesa's window-system code accepts as $XDG_RUNTIME_DIR: an absolute folder of ours, mode 0700."""
    if not path or not os.path.isabs(path):
        return False
    try:
        info = os.stat(path)
    except OSError:
        return False
    return stat.S_ISDIR(info.st_mode) and info.st_uid == os.getuid() and stat.S_IMODE(info.st_mode) == 0o700


def private_runtime_dir() -> str:
    """A folder of this user's only (mode 0700) in the temp dir: ``wgpuviewer-runtime-UID``, or a fresh one."""
    path = os.path.join(tempfile.gettempdir(), f"wgpuviewer-runtime-{os.getuid()}")
    try:
        os.mkdir(path, 0o700)
    except FileExistsError:
        pass
    except OSError:
        return tempfile.mkdtemp(prefix="wgpuviewer-runtime-")
    return path if _runtime_dir_ok(path) else tempfile.mkdtemp(prefix="wgpuviewer-runtime-")


def prepare_driver_environment() -> None:
    """What the GPU drivers read from the environment, set before the first adapter request (importing wgpu loads
    no driver; the first request does): on POSIX a private ``$XDG_RUNTIME_DIR`` when it is unset or invalid (Mesa
    prints four ``error: XDG_RUNTIME_DIR is invalid`` lines otherwise). Idempotent."""
    if os.name == "posix" and not _runtime_dir_ok(os.environ.get("XDG_RUNTIME_DIR")):
        os.environ["XDG_RUNTIME_DIR"] = private_runtime_dir()
