"""The header every report.md starts with: what was run (the command line), on what (the adapter), when and for
how long, and which suite; ``Clock`` times a run for it."""

from __future__ import annotations

import datetime
import time
from dataclasses import dataclass


@dataclass(frozen=True)
class Header:
    title: str
    command: str  # the command line, as ``study.command_line`` builds it
    adapter: str  # the GPU adapter's summary
    suite: str
    started: datetime.datetime | None  # None: a report regenerated from results files
    seconds: float | None
    sources: tuple[str, ...] = ()  # the results files a regenerated report comes from

    def lines(self) -> list[str]:
        """The title and one list item per field (markdown); the report continues the list or starts a paragraph."""
        if self.started is None:
            date = "not recorded in the results; report regenerated from " + (", ".join(self.sources) or "results")
        else:
            date = f"{self.started:%Y-%m-%d %H:%M} UTC"
        duration = "–" if self.seconds is None else f"{self.seconds:.0f} s"
        return [f"# {self.title}", "", f"- command: `{self.command}`", f"- adapter: **{self.adapter}**",
                f"- suite: `{self.suite}`", f"- date: {date}", f"- duration: {duration}"]


class Clock:
    """Started when made: the start time (UTC) and the seconds since, for the report's header."""

    def __init__(self):
        self.started = datetime.datetime.now(datetime.UTC)
        self._start = time.perf_counter()

    @property
    def seconds(self) -> float:
        return time.perf_counter() - self._start

    def header(self, title: str, command: str, adapter: str, suite: str) -> Header:
        return Header(title, command, adapter, suite, self.started, self.seconds)
