"""``wgpuviewer docs [--check]``: every generated block of README.md and docs/*.md written again from its one source,
by this explicit command (no measurement writes the checkout's pages).

A block is the text between a ``<!-- generated: NAME -->`` line and the next ``<!-- end generated -->`` line; each
(page, NAME) has one source in ``BLOCKS``: a registry's table (techniques, filters, map kinds, viewer keys) or a
committed results folder (the README's headline from the newest ``./dev gpu-suite`` run under ``benchmarks/``; each
study folder's ``docs.py`` ``BLOCKS``, e.g. docs/filtering.md's numbers from ``benchmarks/filtering_lavapipe/``).
A marker with no source, or a source whose marker is missing from its page, is an error: a block is never silently
left alone. Pages are written atomically and only when a block changed; ``--check`` writes nothing and exits 1
naming every block that differs.

In the lab room: it may import anything of the product, bench, the harness and the studies (their report code is
the source of their blocks).
"""

from __future__ import annotations

import importlib
import importlib.util
import pkgutil
import re
import sys
from pathlib import Path

from wgpuviewer.core.errors import UserError
from wgpuviewer.core.io import write_bytes
from wgpuviewer.lab.harness.blocks import Block
from wgpuviewer.lab.harness.study import STUDIES_PACKAGE

CHECKOUT = Path(__file__).resolve().parents[2]
BEGIN = "<!-- generated: {name} -->"
END = "<!-- end generated -->"
MARKER = re.compile(r"^<!-- generated: (.+?) -->$", re.MULTILINE)  # on a line of its own (not quoted in prose)


def _techniques(root: Path) -> str:
    from wgpuviewer.techniques import markdown_table

    return markdown_table().strip()


def _filters(root: Path) -> str:
    from wgpuviewer.relief.filters import markdown_table

    return markdown_table().strip()


def _map_kinds(root: Path) -> str:
    from maptools.registry import markdown_table

    return markdown_table().strip()


def _keys(root: Path) -> str:
    from wgpuviewer.viewer.keys import markdown_table

    return markdown_table().strip()


def _headline(root: Path) -> str:
    from wgpuviewer.lab.gpusuite import headline_markdown

    return headline_markdown(root / "benchmarks", root)


OWN_BLOCKS = (
    Block("README.md", "headline", "the newest ./dev gpu-suite run under benchmarks/", _headline),
    Block("README.md", "techniques", "the technique registry", _techniques),
    Block("README.md", "filters", "the filter registry", _filters),
    Block("README.md", "map kinds", "the map-kind registry", _map_kinds),
    Block("docs/usage.md", "viewer keys", "the viewer's key table", _keys),
)


def study_blocks(package: str = STUDIES_PACKAGE) -> tuple[Block, ...]:
    """``BLOCKS`` of every study folder's ``docs`` module (a study without one publishes no block)."""
    found = []
    for info in sorted(pkgutil.iter_modules(importlib.import_module(package).__path__), key=lambda m: m.name):
        if info.ispkg and importlib.util.find_spec(f"{package}.{info.name}.docs") is not None:
            found.extend(importlib.import_module(f"{package}.{info.name}.docs").BLOCKS)
    return tuple(found)


BLOCKS = OWN_BLOCKS + study_blocks()


def pages(root: Path) -> list[Path]:
    """README.md and docs/*.md of the checkout at ``root`` (those that exist)."""
    return [p for p in [root / "README.md", *sorted((root / "docs").glob("*.md"))] if p.is_file()]


def replace_block(text: str, name: str, body: str, page: str = "the page") -> str:
    """``text`` with block ``name``'s lines between its marker lines replaced by ``body``."""
    begin = BEGIN.format(name=name)
    found = list(re.finditer(f"^{re.escape(begin)}$", text, re.MULTILINE))
    end = re.compile(f"^{re.escape(END)}$", re.MULTILINE).search(text, found[0].end()) if len(found) == 1 else None
    if end is None:
        raise UserError(f"{page}: needs one {begin!r} line followed by an {END!r} line; add them where the block goes")
    return f"{text[:found[0].start()]}{begin}\n{body}\n{END}{text[end.end():]}"


def regenerate(root: Path, page: Path) -> tuple[str, str, list[str]]:
    """(the page's text, the text with every block made again, the names of the blocks that differ)."""
    relative = page.relative_to(root).as_posix()
    text = page.read_text(encoding="utf-8")
    known = {b.name: b for b in BLOCKS if b.page == relative}
    found = MARKER.findall(text)
    unknown = [name for name in found if name not in known]
    if unknown:
        raise UserError(f"{relative}: generated block {unknown[0]!r} has no source in wgpuviewer.lab.docs.BLOCKS; add "
                        "one or remove its markers")
    missing = [name for name in known if name not in found]
    if missing:
        raise UserError(f"{relative}: has no {BEGIN.format(name=missing[0])!r} marker for its generated block; add "
                        f"it and {END!r}")
    new, changed = text, []
    for name, block in known.items():
        old = new
        new = replace_block(new, name, block.body(root), relative)
        if new != old:
            changed.append(name)
    return text, new, changed


def run(root: Path, check: bool) -> int:
    """Every block of every page made again (written unless ``check``); prints what differed. 1: ``check`` found a
    block that differs."""
    stale = []
    for page in pages(root):
        text, new, changed = regenerate(root, page)
        relative = page.relative_to(root).as_posix()
        for name in changed:
            block = next(b for b in BLOCKS if b.page == relative and b.name == name)
            verb = "differs from" if check else "regenerated from"
            stale.append(f"{relative}: block {name!r} {verb} {block.source}")
        if changed and not check:
            write_bytes(page, new.encode("utf-8"))
    for line in stale:
        print(line)
    if not stale:
        print("every generated block is up to date")
    elif check:
        print("run `wgpuviewer docs` to regenerate them", file=sys.stderr)
    return 1 if check and stale else 0


class Docs:
    name = "docs"
    help = "regenerate every generated block of README.md and docs/*.md from its source (--check: only compare)"

    def add_arguments(self, parser) -> None:
        parser.add_argument("--check", action="store_true",
                            help="write nothing; exit 1 naming each block that differs from its source")
        parser.add_argument("--root", default=str(CHECKOUT),
                            help="the checkout whose README.md and docs/*.md are made again, from its registries and "
                            "benchmarks/ (default: this one)")

    def command(self, args) -> int:
        root = Path(args.root)
        if not (root / "README.md").is_file():
            raise UserError(f"--root {root}: no README.md there; give a checkout of wgpuviewer")
        return run(root, args.check)


COMMAND = Docs()


def register(subparsers) -> None:
    """``wgpuviewer docs`` on the command line's ``subparsers``."""
    parser = subparsers.add_parser(COMMAND.name, help=COMMAND.help)
    COMMAND.add_arguments(parser)
    parser.set_defaults(func=COMMAND.command)
