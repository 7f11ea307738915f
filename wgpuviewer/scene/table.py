"""Reading a scene's TOML: ``Table``, one table being read, with typed getters (number, vector, direction,
string, boolean, nested tables, a path relative to the scene) whose errors are one line naming the file, the key
path, the value and what is expected; ``show_value``, a value as messages show it; ``reject_non_finite`` (TOML
allows nan and inf, scenes do not).
"""

from __future__ import annotations

import math
from pathlib import Path

from wgpuviewer.core.errors import FileError, UserError
from wgpuviewer.core.images import resolve_path

from .model import Vec3, normalise

#: ``default`` of a getter whose key is required.
MISSING = object()


def show_value(value) -> str:
    """repr of a value for messages: one line, bounded length."""
    text = repr(value)
    return text if len(text) <= 80 else text[:77] + "..."


def _range_text(lo: float | None, hi: float | None, exclusive: bool) -> str:
    if lo is not None and hi is not None:
        return f"expected {lo:g} to {hi:g}" + (" (exclusive)" if exclusive else "")
    if lo is not None:
        return f"expected {'>' if exclusive else '>='} {lo:g}"
    return f"expected {'<' if exclusive else '<='} {hi:g}"


def _in_range(x: float, lo: float | None, hi: float | None, exclusive: bool) -> bool:
    if exclusive:
        return (lo is None or x > lo) and (hi is None or x < hi)
    return (lo is None or x >= lo) and (hi is None or x <= hi)


def is_number(x) -> bool:
    return isinstance(x, (int, float)) and not isinstance(x, bool)


class Table:
    """One TOML table being read: typed getters whose errors carry the file and key path."""

    def __init__(self, src: str, key: str, data, allowed: tuple[str, ...]):
        if not isinstance(data, dict):
            raise UserError(f"{src}: {key} = {show_value(data)}: expected a table")
        self.src, self.key, self.data = src, key, data
        for name, value in data.items():
            if name not in allowed:
                raise self.error(name, value, f"unknown key; allowed: {', '.join(allowed) or 'none'}")

    def path(self, name: str) -> str:
        return f"{self.key}.{name}" if self.key else name

    def error(self, name: str, value, expected: str) -> UserError:
        return UserError(f"{self.src}: {self.path(name)} = {show_value(value)}: {expected}")

    def get(self, name: str, default, expected: str):
        """The raw value, ``default`` if absent; a missing key without default is an error."""
        if name in self.data:
            return self.data[name]
        if default is MISSING:
            raise UserError(f"{self.src}: {self.path(name)}: missing required key; expected {expected}")
        return default

    def number(self, name, default=MISSING, lo=None, hi=None, exclusive=False) -> float:
        value = self.get(name, default, "a number")
        if not is_number(value):
            raise self.error(name, value, "expected a number")
        if not _in_range(value, lo, hi, exclusive):
            raise self.error(name, value, f"out of range, {_range_text(lo, hi, exclusive)}")
        return float(value)

    def vector(self, name, n, default=MISSING, lo=None, hi=None, exclusive=False) -> tuple[float, ...]:
        value = self.get(name, default, f"an array of {n} numbers")
        if not (isinstance(value, (list, tuple)) and len(value) == n and all(map(is_number, value))):
            raise self.error(name, value, f"expected an array of {n} numbers")
        if not all(_in_range(x, lo, hi, exclusive) for x in value):
            raise self.error(name, value, f"out of range, {n} numbers each {_range_text(lo, hi, exclusive)}")
        return tuple(float(x) for x in value)

    def direction(self, name, default=MISSING) -> Vec3:
        value = self.vector(name, 3, default)
        if math.hypot(*value) < 1e-9:
            raise self.error(name, list(value), "zero vector; expected a nonzero direction")
        return normalise(value)

    def string(self, name, default=MISSING, choices: tuple[str, ...] = ()) -> str:
        value = self.get(name, default, f"one of {', '.join(choices)}" if choices else "a string")
        if not isinstance(value, str):
            raise self.error(name, value, "expected a string")
        if choices and value not in choices:
            raise self.error(name, value, f"expected one of {', '.join(choices)}")
        return value

    def boolean(self, name, default=MISSING) -> bool:
        value = self.get(name, default, "true or false")
        if not isinstance(value, bool):
            raise self.error(name, value, "expected true or false")
        return value

    def file_path(self, name: str, value: str, base: Path) -> Path:
        """The absolute path of the file or folder ``value`` of key ``name`` (relative to ``base``, the scene's
        folder; ``~`` expanded); a symbolic link loop on the way is an error naming the key."""
        try:
            return resolve_path(base / Path(value).expanduser())  # base is ignored for an absolute value
        except FileError as error:
            raise self.error(name, value, error.reason) from None

    def array_of_tables(self, name: str) -> list:
        """``[[name]]`` entries; [] when absent."""
        value = self.data.get(name, [])
        if not (isinstance(value, list) and all(isinstance(x, dict) for x in value)):
            raise self.error(name, value, f"expected an array of tables ([[{name}]])")
        return value

    def table_of_tables(self, name: str) -> dict:
        """``[name.KEY]`` sections as {KEY: raw table}; {} when absent."""
        value = self.data.get(name, {})
        if not isinstance(value, dict):
            raise self.error(name, value, f"expected tables ([{name}.NAME])")
        return value


def reject_non_finite(value, src: str, key: str) -> None:
    """TOML allows nan and inf; no scene value may be either."""
    if isinstance(value, float) and not math.isfinite(value):
        raise UserError(f"{src}: {key} = {value!r}: expected a finite number")
    if isinstance(value, dict):
        for name, item in value.items():
            reject_non_finite(item, src, f"{key}.{name}" if key else name)
    elif isinstance(value, list):
        for i, item in enumerate(value):
            reject_non_finite(item, src, f"{key}[{i}]")
