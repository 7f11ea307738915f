"""``wgpuviewer perspective --threads-only``: only the threaded timing (the suite's first speed frame), into
threads.csv and a report.md of its own (``threads_report`` makes the rows and the section)."""

from __future__ import annotations

import os
import platform
import sys
from pathlib import Path

from wgpuviewer.core.io import write_bytes
from wgpuviewer.lab.harness import suite as harness_suite
from wgpuviewer.lab.harness.header import Clock

from .compiled import cpu_model, numba_module
from .geometry import Quad, Setup, build
from .run import SUITES, SWEEP_TILT, configured
from .threaded import THREADS_TABLE
from .threads_report import THREADS_FILE, TITLE, measure_suite, section


def first_frame_quad(suite) -> Quad:
    """The grazing quad of the suite's first speed frame, at the study's texel density."""
    frame = suite.speed_frames[0]
    return build(configured(Setup(span_length=frame[0], rows=frame[1], tilt=SWEEP_TILT)))


def run_threads(suite_name: str, out: Path, backend: str | None = None, progress: bool = True,
                command: str = "wgpuviewer perspective --threads-only") -> list[dict]:
    """Only the threaded timing (the suite's first speed frame): threads.csv and report.md into ``out``."""
    suite = harness_suite.pick(SUITES, suite_name)
    clock = Clock()
    if progress:
        print(f"perspective threads: {suite.speed_frames[0]}, {suite.compiled_repeats} rounds", file=sys.stderr)
    rows = measure_suite(suite, first_frame_quad(suite))
    THREADS_TABLE.write(Path(out) / THREADS_FILE, rows)
    header = clock.header(TITLE, command, "none (CPU loops only)", suite.name)
    lines = [*header.lines(), f"- CPU: {cpu_model()}, {os.cpu_count()} logical CPUs · Python "
             f"{platform.python_version()}, numba {numba_module().__version__}", "", *section(rows), ""]
    write_bytes(Path(out) / "report.md", "\n".join(lines).encode("utf-8"))
    return rows

