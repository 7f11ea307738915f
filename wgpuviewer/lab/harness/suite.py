"""The smoke/full suite every measurement command has: ``smoke`` runs in minutes on a software adapter (CI, the
tests), ``full`` is the measurement a report publishes. A command's suites derive from ``Suite``; ``suites``
makes its table of them and ``pick`` resolves ``--suite``."""

from __future__ import annotations

from dataclasses import dataclass

from wgpuviewer.core.errors import UserError

NAMES = ("smoke", "full")


@dataclass(frozen=True)
class Suite:
    name: str  # one of NAMES


def suites(*items: Suite) -> dict[str, Suite]:
    """The suites by name; exactly one of each of ``NAMES``."""
    table = {s.name: s for s in items}
    if sorted(table) != sorted(NAMES) or len(items) != len(NAMES):
        raise ValueError(f"suites {[s.name for s in items]}: expected one each of {', '.join(NAMES)}")
    return table


def pick(table: dict[str, Suite], name: str) -> Suite:
    """``table[name]``; a UserError naming ``--suite`` for another name."""
    if name not in table:
        raise UserError(f"--suite {name!r}: unknown; expected one of {', '.join(table)}")
    return table[name]
