"""A typed results table: columns declared once (name, type, unit, format), written as CSV atomically and read back
into rows whose values have the declared types again.

An empty cell of a number or flag column is ``None`` (a value that does not apply to the row); of a text column,
the empty text. A float that is not a number is written ``nan``. A column added after some files were written is
``optional``: those files read with its ``default``.
"""

from __future__ import annotations

import csv
import io
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path

from wgpuviewer.core.errors import UserError
from wgpuviewer.core.io import write_bytes

TYPES = (str, int, float, bool)


@dataclass(frozen=True)
class Column:
    name: str
    type: type = float
    unit: str = ""  # what a number counts (texels, ms, dB, ...); documentation for readers of the CSV
    format: str = ".6g"  # how a float is written
    optional: bool = False  # files written before the column existed lack it
    default: object = None  # what rows of such files hold

    def __post_init__(self):
        if self.type not in TYPES:
            raise TypeError(f"column {self.name!r}: type {self.type!r}; expected one of str, int, float, bool")

    def cell(self, value) -> str:
        """``value`` as this column's CSV text (ValueError when it is not of the column's type)."""
        if value is None:
            return ""
        if self.type is float:
            return format(float(value), self.format)
        if self.type is int:
            if isinstance(value, bool) or not float(value).is_integer():
                raise ValueError(f"column {self.name!r}: {value!r} is not a whole number")
            return str(int(value))
        if self.type is bool:
            if value not in (True, False):
                raise ValueError(f"column {self.name!r}: {value!r} is not true or false")
            return str(bool(value))
        return str(value)

    def parse(self, text: str):
        """The typed value of a CSV cell (ValueError naming what was expected)."""
        if text == "":
            return "" if self.type is str else None
        if self.type is float:
            return float(text)
        if self.type is int:
            return int(text)
        if self.type is bool:
            if text not in ("True", "False"):
                raise ValueError("expected True or False")
            return text == "True"
        return text



def columns(type_: type, unit: str, *names: str) -> tuple[Column, ...]:
    """Columns ``names`` of one type and unit, in that order."""
    return tuple(Column(name, type_, unit) for name in names)


class Table:
    """The columns of one kind of results file (``what`` names it in error messages, e.g. "benchmark results")."""

    def __init__(self, what: str, columns: Iterable[Column]):
        self.what = what
        self.columns = tuple(columns)
        self.names = tuple(c.name for c in self.columns)
        if len(set(self.names)) != len(self.names):
            raise ValueError(f"{what}: a column is declared twice")
        self.by_name = {c.name: c for c in self.columns}

    def blank(self) -> dict:
        """A row with every column and no values (None; the empty text in text columns)."""
        return {c.name: "" if c.type is str else None for c in self.columns}

    def text(self, rows: Iterable[dict]) -> str:
        """``rows`` (dicts holding at least every column) as CSV text with a header line."""
        buffer = io.StringIO(newline="")
        writer = csv.writer(buffer, lineterminator="\n")
        writer.writerow(self.names)
        for row in rows:
            missing = [n for n in self.names if n not in row]
            if missing:
                raise ValueError(f"{self.what}: a row lacks the column(s) {', '.join(missing)}")
            writer.writerow([c.cell(row[c.name]) for c in self.columns])
        return buffer.getvalue()

    def write(self, path, rows: Iterable[dict]) -> None:
        """``rows`` as a CSV file at ``path``, atomically (core.io)."""
        write_bytes(path, self.text(rows).encode("utf-8"))

    def read(self, path) -> list[dict]:
        """The rows of a CSV file written by ``write`` (or before an optional column existed), typed; a file that is
        not such a table is a UserError naming the file, the line and the column."""
        path = Path(path)
        try:
            with open(path, newline="", encoding="utf-8") as f:
                lines = list(csv.reader(f))
        except (OSError, UnicodeDecodeError) as error:
            raise UserError(f"{path}: cannot read {self.what} ({getattr(error, 'strerror', None) or error})") from None
        if not lines:
            raise UserError(f"{path}: empty; expected {self.what} with the header line {','.join(self.names)}")
        header = lines[0]
        unknown = [n for n in header if n not in self.by_name]
        absent = [c.name for c in self.columns if c.name not in header and not c.optional]
        if unknown or absent or len(set(header)) != len(header):
            problem = (f"unknown column(s) {', '.join(map(repr, unknown))}" if unknown else
                       f"no column(s) {', '.join(map(repr, absent))}" if absent else "a column appears twice")
            raise UserError(f"{path}: {problem}; expected {self.what} with the columns {', '.join(self.names)}")
        rows = []
        for number, cells in enumerate(lines[1:], start=2):
            if len(cells) != len(header):
                raise UserError(f"{path}, line {number}: {len(cells)} cells; the header has {len(header)}")
            given = dict(zip(header, cells))
            row = {}
            for column in self.columns:
                if column.name not in given:
                    row[column.name] = column.default
                    continue
                try:
                    row[column.name] = column.parse(given[column.name])
                except ValueError:
                    raise UserError(f"{path}, line {number}: column {column.name!r}: {given[column.name]!r} is not "
                                    f"{_a(column.type)}") from None
            rows.append(row)
        return rows


def _a(kind: type) -> str:
    return {str: "text", int: "a whole number", float: "a number", bool: "True or False"}[kind]

