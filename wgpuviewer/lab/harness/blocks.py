"""A generated block of README.md or docs/*.md: the text between a ``<!-- generated: NAME -->`` line and the next
``<!-- end generated -->`` line, made by one function from one source. ``wgpuviewer docs`` (``wgpuviewer.lab.docs``)
collects its own blocks (the registries' tables, the headline) and every study folder's ``docs.py`` ``BLOCKS``, so
a study publishes its numbers without a list to edit elsewhere.
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
    results: str | None = None  # the results folder it is made from, relative to the checkout (None: a registry)
