"""A generated block of README.md or docs/*.md: the text between a ``<!-- generated: NAME -->`` line and the next
``<!-- end generated -->`` line, made by one function from one source. ``wgpuviewer docs`` (``wgpuviewer.lab.docs``)
collects its own blocks (the registries' tables, the headline) and every study folder's ``docs.py`` ``BLOCKS``, so
a study publishes its numbers without a list to edit elsewhere. A block made from a results folder names it
(``results``): ``wgpuviewer docs`` then starts it with the folder's stale label when the folder's code fingerprint
is not today's (``wgpuviewer.lab.results``).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path


@dataclass(frozen=True)
class Block:
    page: str  # relative to the checkout, e.g. "docs/filtering.md"
    name: str  # the marker's NAME
    source: str  # what it is generated from, in words
    body: Callable[[Path], str]  # the checkout's root -> the text between the markers (without them)
    # the results folder it is made from, relative to the checkout (None: a registry); or the checkout's root -> it,
    # for a block whose folder is chosen among several (the README's headline)
    results: str | Callable[[Path], str | None] | None = None

    def folder(self, root: Path) -> str | None:
        """The results folder the block is made from in the checkout at ``root`` (None: a registry)."""
        return self.results(root) if callable(self.results) else self.results
