"""The project's environment variables, each parsed in one place for every command and library call:

- ``WGPUVIEWER_BACKEND``: the wgpu backend when no ``--backend`` is given (auto, vulkan, metal, dx12, gl);
- ``WGPUVIEWER_CACHE_DIR``: the map cache folder (default ``~/.cache/wgpuviewer/maps``);
- ``WGPUVIEWER_CACHE_MAX``: the map cache's size cap (500M, 2G, 1.5T, bytes; 0 turns the cap off; default 2G);
- ``WGPUVIEWER_CONFIG_DIR``: the viewer's settings folder (default: the platform's config folder).

An empty value is the same as an unset one; ``~`` in a path is the home folder. A bad value is a ``UserError``
naming the variable, the value and the fix. Both CLIs check every variable before their command runs
(``core.cli.run_command``), so no command accepts a value another refuses, whether or not it reaches the code that
uses it. Variables of other systems (DISPLAY, WAYLAND_DISPLAY, XDG_*, APPDATA, OPENCV_*) are read where they are
used, as those systems define them.

Also what the GPU drivers read from the environment (``prepare_driver_environment``: a private
``$XDG_RUNTIME_DIR``), set by both CLIs and by the first adapter request of a library call.

Standard library only: ``core.cli`` imports this before any GPU driver loads.
"""

from __future__ import annotations

import os
import re
import stat
import tempfile
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from .errors import UserError

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


@dataclass(frozen=True)
class Variable:
    """One environment variable: ``parse`` turns a set value into what it means (ValueError: what is expected);
    ``default`` is used when it is unset or empty, ``default_text`` says what that is in errors."""

    name: str
    parse: Callable[[str], Any]
    default: Any
    default_text: str

    def raw(self) -> str | None:
        """The value as set, None when unset or empty."""
        text = os.environ.get(self.name)
        return text if text and text.strip() else None

    def value(self):
        """What the variable means now (read each call: tests and embedding programs change the environment)."""
        text = self.raw()
        if text is None:
            return self.default
        try:
            return self.parse(text)
        except ValueError as error:
            raise UserError(f"${self.name} = {text!r}: {error}; set a valid value or unset it "
                            f"(default: {self.default_text})") from None


#: wgpu backend names (``core.gpu.BACKEND_CHOICES`` is the same tuple, checked by a test).
BACKEND_CHOICES = ("auto", "vulkan", "metal", "dx12", "gl")

BACKEND = Variable("WGPUVIEWER_BACKEND", _choice(BACKEND_CHOICES), "auto", "auto")
CACHE_DIR = Variable("WGPUVIEWER_CACHE_DIR", _path, None, "~/.cache/wgpuviewer/maps")
CACHE_MAX = Variable("WGPUVIEWER_CACHE_MAX", parse_bytes, 2 * 2**30, "2G")
CONFIG_DIR = Variable("WGPUVIEWER_CONFIG_DIR", _path, None, "the platform's config folder")

VARIABLES = (BACKEND, CACHE_DIR, CACHE_MAX, CONFIG_DIR)


def check_environment() -> None:
    """Parse every variable: the first bad one is a UserError."""
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
