"""``Discovered``: a read-only table (name -> entry) that registries find in their folders on first use, not at
import (a folder's module may import the registry that finds it), and find again when what they search changes.

Imports nothing else of the project.
"""

from __future__ import annotations

from collections.abc import Callable, Hashable, Iterator, Mapping
from typing import Generic, TypeVar

Entry = TypeVar("Entry")


class Discovered(Mapping[str, Entry], Generic[Entry]):
    """``find()`` builds the table on first use, and again whenever ``searched()`` (e.g. a package's search path)
    differs from what it was at the last build."""

    def __init__(self, name: str, find: Callable[[], dict[str, Entry]],
                 searched: Callable[[], Hashable] = lambda: None) -> None:
        self._name, self._find, self._searched = name, find, searched
        self._table: dict[str, Entry] | None = None
        self._seen: Hashable = None

    def _entries(self) -> dict[str, Entry]:
        searched = self._searched()
        if self._table is None or searched != self._seen:
            self._table, self._seen = self._find(), searched
        return self._table

    def __getitem__(self, name: str) -> Entry:
        return self._entries()[name]

    def __iter__(self) -> Iterator[str]:
        return iter(self._entries())

    def __len__(self) -> int:
        return len(self._entries())

    def __repr__(self) -> str:
        return f"{self._name}({', '.join(self._entries())})"
