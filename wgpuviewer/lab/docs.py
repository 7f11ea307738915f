"""``wgpuviewer docs [--check]``: every generated block of README.md and docs/*.md written again from its one source,
by this explicit command (no measurement writes the checkout's pages); and ``wgpuviewer results [--check]``: every
results folder under ``benchmarks/`` as fresh or stale (``lab.results``), ``--check`` exiting 1 naming the folders
whose blocks differ from what their results and freshness make (a change to measured code fails it until the docs
say the folder is stale, or it is measured again; it measures nothing).

A block is the text between a ``<!-- generated: NAME -->`` line and the next ``<!-- end generated -->`` line; each
(page, NAME) has one source in ``BLOCKS``: a registry's table (techniques, filters, map kinds, viewer keys) or a
committed results folder (the README's headline from the widest ``./dev gpu-suite`` run under ``benchmarks/``;
bench's runs, ``lab.bench.docs``; each study folder's ``docs.py`` ``BLOCKS``, e.g. docs/filtering.md's numbers
from ``benchmarks/filtering_lavapipe/``).
A block made from a results folder whose code fingerprint is not today's starts with the folder's stale label
(``results.stale_note``: measured on the code of DATE; stale since WHAT changed), added here for every block alike.
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
from wgpuviewer.lab import results
from wgpuviewer.lab.harness import stamp
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


def _headline_folder(root: Path) -> str | None:
    from wgpuviewer.lab.gpusuite import headline_run, load_runs

    run = headline_run(load_runs(root / "benchmarks"))
    return None if run is None else run.results.parent.relative_to(root).as_posix()


OWN_BLOCKS = (
    Block("README.md", "headline", "the widest ./dev gpu-suite run under benchmarks/", _headline,
          results=_headline_folder),
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


def bench_blocks() -> tuple[Block, ...]:
    """bench's blocks (``lab.bench.docs``: its committed runs' headlines and fetch tables)."""
    from wgpuviewer.lab.bench.docs import BLOCKS as BENCH

    return BENCH


BLOCKS = OWN_BLOCKS + bench_blocks() + study_blocks()


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


def body(block: Block, root: Path) -> str:
    """The block's text: its source's, after its folder's stale label when the folder is not fresh; while the folder
    holds no results (no CSV: a run in progress, or none yet), a line saying so."""
    folder = block.folder(root)
    if folder is not None and not any((root / folder).glob("*.csv")):
        return f"`{folder}/` holds no results yet: run its command, then `wgpuviewer docs`."
    text = block.body(root)
    note = results.stale_note(root, folder) if folder is not None else None
    return text if note is None else f"{note}\n\n{text.lstrip(chr(10))}"


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
        new = replace_block(new, name, body(block, root), relative)
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


def check_results(root: Path) -> list[str]:
    """The folders whose generated blocks differ from what their results and freshness make, with the blocks."""
    bad = []
    for page in pages(root):
        relative = page.relative_to(root).as_posix()
        for name in regenerate(root, page)[2]:
            block = next(b for b in BLOCKS if b.page == relative and b.name == name)
            folder = block.folder(root)
            if folder is not None:
                bad.append(f"{folder}: {results.freshness(root, folder).status()}; its block {name!r} on {relative} "
                           "differs from what it makes")
    return bad


class Results:
    name = "results"
    help = "list every results folder under benchmarks/ as fresh or stale (--check: exit 1 on a stale generated block)"

    def add_arguments(self, parser) -> None:
        parser.add_argument("--check", action="store_true",
                            help="exit 1 naming each folder whose generated blocks differ from what its results and "
                            "freshness make (run `wgpuviewer docs`, or measure it again)")
        parser.add_argument("--stamp-from-git", nargs="+", metavar="FOLDER",
                            help="write FOLDER/stamp.json from git for folders measured before stamps existed")
        parser.add_argument("--root", default=str(CHECKOUT), help="the checkout (default: this one)")

    def command(self, args) -> int:
        root = Path(args.root)
        if not (root / results.BENCHMARKS).is_dir():
            raise UserError(f"--root {root}: no {results.BENCHMARKS}/ there; give a checkout of wgpuviewer")
        for folder in args.stamp_from_git or ():
            if not (root / folder).is_dir():
                raise UserError(f"--stamp-from-git {folder}: no such folder under {root}")
            stamp.write(root / folder, results.stamp_from_git(root, folder))
        if args.check:
            bad = check_results(root)
            for line in bad:
                print(line)
            if bad:
                print("run `wgpuviewer docs` (the blocks then say they are stale), or measure again", file=sys.stderr)
                return 1
            print("every block made from results is what its results and their freshness make")
            return 0
        print("\n".join(results.listing(root)))
        return 0


RESULTS = Results()


def register(subparsers) -> None:
    """``wgpuviewer docs`` and ``wgpuviewer results`` (``lab.results``, the freshness of what the blocks are made
    from) on the command line's ``subparsers``."""
    for command in (COMMAND, RESULTS):
        parser = subparsers.add_parser(command.name, help=command.help)
        command.add_arguments(parser)
        parser.set_defaults(func=command.command)
