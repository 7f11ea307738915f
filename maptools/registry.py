"""The map kinds: the entry type (options, CPU and GPU functions, cross-check tolerance, writer) and their discovery.

Each kind is one folder ``maptools/kinds/KIND/`` whose ``__init__`` exposes ``KIND``, its entry; ``KINDS`` finds
them (no list to edit), ordered by ``Kind.order``, then by name.
"""

from __future__ import annotations

import hashlib
import importlib
import math
import pkgutil
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from wgpuviewer.core.compute import source_hash
from wgpuviewer.core.errors import UserError


@dataclass(frozen=True)
class Option:
    name: str
    default: Any
    type: type
    help: str
    choices: tuple | None = None
    lo: float | None = None
    hi: float | None = None

    def validate(self, kind: str, value: Any) -> Any:
        try:
            v = self.type(value)
            if self.type is int and isinstance(value, float) and not float(value).is_integer():
                raise ValueError
        except (TypeError, ValueError):
            raise UserError(f"{kind}: option {self.name}={value!r} is not a valid {self.type.__name__}") from None
        if self.type is float and not math.isfinite(v):
            raise UserError(f"{kind}: option {self.name} must be finite, got {value!r}")
        if self.choices is not None and v not in self.choices:
            raise UserError(f"{kind}: option {self.name}={value!r}; expected one of {', '.join(map(str, self.choices))}")
        if (self.lo is not None and v < self.lo) or (self.hi is not None and v > self.hi):
            raise UserError(f"{kind}: option {self.name}={value!r} out of range [{self.lo}, {self.hi}]")
        return v


@dataclass(frozen=True)
class Comparison:
    max_diff: float
    mean_diff: float
    ok: bool
    detail: str = ""


@dataclass(frozen=True)
class Case:
    """Option values the kind's GPU path is cross-checked on against its CPU twin (tests/maptools), on every test
    map of at most ``max_texels`` texels (None: all; a bound keeps slow CPU twins to small maps)."""

    options: dict
    max_texels: int | None = None


@dataclass(frozen=True)
class SampledReference:
    """A kind's CPU reference at given values: ``values(height, index, **opts)`` is exactly
    ``kind.cpu(height, **opts)[index]`` for a tuple of integer index arrays, without computing the whole map;
    ``shape(height_shape, opts)`` is the whole map's shape (the GPU map must have it). ``maptools check`` compares
    such a kind at a seeded sample of values by default."""

    values: Callable[..., np.ndarray]
    shape: Callable[[tuple[int, int], dict], tuple[int, ...]]


@dataclass(frozen=True)
class Bench:
    """``maptools bench``'s sizes of a kind that is not timed at ``--sizes``: its own flag (``attr``: the
    argparse destination), that flag's default and help, and the options it is timed with."""

    attr: str
    default: str
    help: str
    options: dict


@dataclass(frozen=True)
class Kind:
    name: str
    description: str
    options: tuple[Option, ...]
    cpu: Callable
    gpu: Callable
    compare: Callable[[Any, Any, dict], Comparison]
    tolerance: str
    writer: Callable[[Any, Any, str, int], None]  # (file object, result, extension, bits)
    extensions: tuple[str, ...]  # first = default for the batch tool
    check: Callable[[dict], None] = field(default=lambda opts: None)
    cases: tuple[Case, ...] = ()  # its GPU-vs-CPU cross-checks; every kind has some (tests/maptools)
    #: Its place in the registry's order (CLI, README table, ``batch``'s default): by this number, then by name.
    order: int = 0
    #: Where its CPU reference can be computed at given values only (``maptools check`` samples it by default).
    sampled: SampledReference | None = None
    #: (dimensions, dtype) of the array a written file holds, for kinds a scene may name a file for; else None.
    readable: tuple[int, Any] | None = None
    #: A written PNG's array (uint8 or uint16) -> the map as the kind makes it; None: 16-bit values / 257.
    read_png: Callable[[np.ndarray], np.ndarray] | None = None
    #: ``maptools bench``'s own sizes for the kind; None: ``--sizes`` at its defaults.
    bench: Bench | None = None

    @property
    def kernels(self) -> tuple:
        """The kernels (``gpu.MapKernel``: the WGSL files in its folder) its GPU path runs; str() is the file name."""
        return self.gpu.kernels

    def source_hash(self) -> str:
        """sha256 over the composed source of each of its kernels: part of every cache key of the kind, so an
        edited kernel (or a file it includes) never serves a map built by the old one."""
        h = hashlib.sha256()
        for kernel in self.kernels:
            h.update(source_hash(kernel.source()).encode())
        return h.hexdigest()

    def resolve(self, options: dict) -> dict:
        """Options with defaults filled in and validated; unknown names are a UserError."""
        known = {o.name: o for o in self.options}
        unknown = sorted(set(options) - set(known))
        if unknown:
            raise UserError(f"{self.name}: unknown option(s) {', '.join(unknown)}; "
                            f"known: {', '.join(known) or 'none'}")
        out = {o.name: o.validate(self.name, options.get(o.name, o.default)) for o in self.options}
        self.check(out)
        return out


BORDER_HELP = "border handling: repeat (wrap, tiling textures), clamp, reflect (OpenCV's reflect-101)"


def _discover() -> dict[str, Kind]:
    """Every ``maptools/kinds/*/`` folder's ``KIND``, by (order, name); a folder's name is its kind's."""
    from . import kinds

    found = []
    for info in pkgutil.iter_modules(kinds.__path__):
        if not info.ispkg or info.name.startswith("_"):
            continue
        kind = importlib.import_module(f"{kinds.__name__}.{info.name}").KIND
        if kind.name != info.name:
            raise ValueError(f"maptools/kinds/{info.name}/ declares the kind {kind.name!r}; name it after its folder")
        found.append(kind)
    return {k.name: k for k in sorted(found, key=lambda k: (k.order, k.name))}


_kinds: dict[str, Kind] | None = None


def all_kinds() -> dict[str, Kind]:
    """The kinds (the dict ``KINDS`` is), found on first use: a kind's folder imports this module for its types."""
    global _kinds
    if _kinds is None:
        _kinds = _discover()
    return _kinds


def __getattr__(name: str):
    if name == "KINDS":  # ``from maptools.registry import KINDS`` and ``registry.KINDS``: the one dict
        return all_kinds()
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def get_kind(name: str) -> Kind:
    kinds = all_kinds()
    if name not in kinds:
        raise UserError(f"unknown map kind {name!r}; expected one of {', '.join(kinds)}")
    return kinds[name]


def _option_cell(o: Option) -> str:
    return f"`{o.name}` {o.default:g}" if isinstance(o.default, float) else f"`{o.name}` {o.default}"


def markdown_table() -> str:
    """The README's map-kind table: kind, what it is, its options (defaults), its kernels, GPU vs CPU tolerance."""
    rows = ["| kind | what | options (default) | kernels | GPU vs CPU |",
            "|---|---|---|---|---|"]
    for k in all_kinds().values():
        options = ", ".join(map(_option_cell, k.options)) or "—"
        kernels = ", ".join(f"`{f}`" for f in k.kernels)
        cells = (f"`{k.name}`", k.description, options, kernels, k.tolerance)
        rows.append("| " + " | ".join(c.replace("|", "\\|") for c in cells) + " |")  # a | in a cell is escaped
    return "\n".join(rows)
