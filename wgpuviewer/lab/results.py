"""The freshness of the results folders under ``benchmarks/`` (``wgpuviewer results``, registered with ``docs``):
each folder with the command, adapter and date its ``stamp.json`` records (``harness.stamp``) and whether it is
**fresh** (its code fingerprint is today's) or **stale** (naming the parts that changed since); ``stale_note``, the
label ``wgpuviewer docs`` puts beside a stale folder's numbers; and ``stamp_from_git``, the stamp of a folder
measured before stamps existed: the fingerprint of the code at the commit it was measured on (the commit before its
report's date, else the commit that last changed it), read from git.

In the lab room: it may import anything of the product and the harness; ``docs`` imports it.
"""

from __future__ import annotations

import datetime
import functools
import re
import subprocess
from dataclasses import dataclass
from pathlib import Path

from wgpuviewer.core.errors import UserError
from wgpuviewer.lab.harness import stamp

CHECKOUT = Path(__file__).resolve().parents[2]
BENCHMARKS = "benchmarks"
SHOWN = 4  # changed parts named per kind; the rest counted


class GitTree:
    """The files of one commit of the checkout at ``root`` (a ``stamp.Source``)."""

    def __init__(self, root: Path, commit: str):
        self.root, self.commit = Path(root), commit

    def _git(self, *words: str) -> subprocess.CompletedProcess:
        return subprocess.run(["git", "-C", str(self.root), *words], capture_output=True, check=False)

    @functools.cache  # noqa: B019 - one tree per stamping, its files read several times
    def read(self, path: str) -> bytes | None:
        done = self._git("show", f"{self.commit}:{path}")
        return done.stdout if done.returncode == 0 else None

    def listing(self, folder: str) -> list[str]:
        done = self._git("ls-tree", "-r", "--name-only", self.commit, "--", folder)
        return sorted(done.stdout.decode().split()) if done.returncode == 0 else []


def folders(root: Path) -> list[str]:
    """Every results folder under ``benchmarks/`` (one holding a stamp, a report.md or a results.csv), relative to
    ``root``, sorted."""
    base = Path(root) / BENCHMARKS
    found = {p.parent for name in (stamp.STAMP, "report.md", "results.csv") for p in base.rglob(name)}
    return sorted(p.relative_to(root).as_posix() for p in found)


def package_from_command(command: str) -> str:
    """The measuring package a command line ran (``wgpuviewer bench`` or a study's subcommand)."""
    words = command.split()
    name = words[words.index("wgpuviewer") + 1] if "wgpuviewer" in words[:-1] else "bench"
    return "wgpuviewer/lab/bench" if name == "bench" else f"wgpuviewer/lab/studies/{name.replace('-', '_')}"


@dataclass(frozen=True)
class Freshness:
    folder: str  # relative to the checkout
    record: dict | None  # its stamp; None: it has none
    changed: tuple[str, ...]  # the parts whose fingerprint differs now

    @property
    def fresh(self) -> bool:
        return self.record is not None and not self.changed

    @property
    def code_date(self) -> str:
        return self.record["date"][:10] if self.record else "an unknown date"

    def what_changed(self) -> str:
        """The changed parts grouped by kind, e.g. "technique `pom`, `relief`; map `distance`"."""
        if self.record is None:
            return f"unknown (no {stamp.STAMP})"
        if self.record.get("definition") != stamp.DEFINITION:
            return "the fingerprint's definition"
        groups: dict[str, list[str]] = {}
        for part in self.changed:
            kind, _, name = part.partition(" ")
            groups.setdefault(kind, []).append(f"`{name}`")
        return "; ".join(f"{kind} {', '.join(names[:SHOWN])}" + (f" and {len(names) - SHOWN} more" if len(names) > SHOWN
                                                                   else "") for kind, names in groups.items())

    def status(self) -> str:
        if self.record is None:
            return f"stale: fingerprint unknown (no {stamp.STAMP})"
        return "fresh" if self.fresh else f"stale: {self.what_changed()} changed"


def freshness(root: Path, folder: str) -> Freshness:
    """How ``folder``'s stamp compares with the code of the checkout at ``root`` now."""
    record = stamp.read(Path(root) / folder)
    if record is None:
        return Freshness(folder, None, ())
    if record.get("definition") != stamp.DEFINITION:  # its parts may not be today's kinds: not comparable
        return Freshness(folder, record, ("definition",))
    now = stamp.fingerprint(stamp.Files(root), record["parts"])
    return Freshness(folder, record, tuple(p for p, h in record["parts"].items() if now[p] != h))


def stale_note(root: Path, folder: str) -> str | None:
    """The line a generated block made from ``folder`` starts with when the folder is not fresh; None when it is (or
    when there is no such folder: the block itself says so)."""
    state = freshness(root, folder)
    if state.fresh or not (Path(root) / folder).is_dir():
        return None
    if state.record is None:
        return (f"*Measured on code of unknown date and fingerprint: `{folder}/` has no {stamp.STAMP} "
                "(`wgpuviewer results`).*")
    return (f"*Measured on the code of {state.code_date} (`{folder}/`); stale since: {state.what_changed()} "
            "changed (`wgpuviewer results`).*")


def listing(root: Path) -> list[str]:
    """Per results folder three lines: the folder, fresh or stale (what changed); its code's date and adapter; its
    command."""
    lines = []
    for folder in folders(root):
        state = freshness(root, folder)
        r = state.record or {}
        lines.append(f"{folder}: {state.status()}\n  code of {r.get('date', '?')}, on {r.get('adapter', '?')}\n"
                     f"  command: {r.get('command', '?')}")
    return lines


def _git_text(root: Path, *words: str) -> str:
    done = subprocess.run(["git", "-C", str(root), *words], capture_output=True, text=True, check=False)
    return done.stdout.strip() if done.returncode == 0 else ""


_REPORT_DATE = re.compile(r"^- date: (\d{4}-\d{2}-\d{2})[ ,]+(\d{2}:\d{2})", re.MULTILINE)
_REPORT_COMMAND = re.compile(r"^- commands?: `([^`]+)`", re.MULTILINE)


def stamp_from_git(root: Path, folder: str) -> dict:
    """A stamp for a folder measured before stamps existed: the code of the last commit before its report's date
    (else of the commit that last changed its results), its parts fingerprinted as they were in that commit."""
    path = Path(root) / folder
    report = (path / "report.md").read_text(encoding="utf-8") if (path / "report.md").is_file() else ""
    added = _git_text(root, "log", "-1", "--format=%H", "--", folder)
    if not added:
        raise UserError(f"--stamp-from-git {folder}: git has no commit of it; measure it again instead")
    date = _REPORT_DATE.search(report)
    commit = (_git_text(root, "rev-list", "-1", f"--before={date[1]} {date[2]} +0000", added) if date else "") or added
    when = datetime.datetime.fromtimestamp(int(_git_text(root, "show", "-s", "--format=%ct", commit)), datetime.UTC)
    command = _REPORT_COMMAND.search(report)
    command = command[1] if command else "unknown (not in its report)"
    techniques, filters = stamp.used_names(path)
    tree = GitTree(root, commit)
    # today's parts, hashed as they were then: a part that moved since counts as changed
    parts = stamp.parts_for(stamp.Files(root), techniques, filters, package_from_command(command))
    return {"definition": stamp.DEFINITION, "source": f"git {commit[:12]}: the code before the results were measured",
            "command": command, "adapter": stamp.adapter_of(path),
            "date": when.strftime("%Y-%m-%dT%H:%M:%SZ"), "seconds": None,
            "parts": stamp.fingerprint(tree, parts)}
