"""The adaptive-POM study's run: ``measure.measure``, then ``compare.compare``, then results.csv, comparison.csv,
report.md and curves.png (``report``)."""

from __future__ import annotations

from pathlib import Path

from wgpuviewer.core.gpu import get_gpu

from . import compare, measure, report


def run(out: Path, suite_name: str, backend: str | None, progress: bool, command: str) -> None:
    suite, rows, views, clock = measure.measure(suite_name, backend, progress)
    measure.TABLE.write(out / "results.csv", rows)
    comparison = compare.compare(views, suite.resamples)
    compare.TABLE.write(out / "comparison.csv", comparison)
    header = clock.header(measure.TITLE, command, get_gpu(backend, quiet=True).summary, suite.name)
    report.write_report(out, rows, comparison, header, suite)
