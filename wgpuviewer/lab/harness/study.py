"""A study as a ``wgpuviewer`` subcommand: the ``Study`` protocol every study folder exposes as ``STUDY`` (in its
``__init__``), its discovery (every package under ``wgpuviewer.lab.studies``), its registration on the command line
with the options every measuring command shares (the CLI puts the command line, ``core.commands.command_line``, on
``args.command_line`` for the report's header), and ``run_study``, the one order every measuring command runs in:
every option value checked, then the output folder checked and created and the stale temps of a killed earlier
run swept from it, then the measurement (the GPU starts only there), then the folder's ``stamp.json``
(``stamp``: the command, the adapter, the date and the fingerprint of the code, hashed before the measurement).
``StudyCommand`` is the common form of a study's ``STUDY`` (its name, help and suite help; its own options; ``run``
calling the folder's ``run.run``), and ``numbers_within`` checks a comma-separated option of numbers against a
range.

A study's ``__init__`` stays light (no GPU, no heavy imports): the command line imports every study to build
its parser; ``options`` and ``run`` import the measuring code when the command runs.
"""

from __future__ import annotations

import argparse
import functools
import importlib
import inspect
import pkgutil
from pathlib import Path
from typing import Protocol, runtime_checkable

from wgpuviewer.core.commands import add_backend_option
from wgpuviewer.core.io import output_dir, remove_abandoned_temps

from . import stamp
from .header import Clock
from .suite import NAMES

STUDIES_PACKAGE = "wgpuviewer.lab.studies"


@runtime_checkable
class Study(Protocol):
    name: str  # the subcommand, e.g. "refined-distance"
    help: str  # one line for ``wgpuviewer --help``

    def add_arguments(self, parser: argparse.ArgumentParser) -> None:
        """The command's own options (``add_measurement_options`` adds the shared ones)."""

    def options(self, args: argparse.Namespace) -> object:
        """Every option value checked (a UserError naming the option and the fix) into what ``run`` takes; creates
        no file and starts no GPU. ``args.command_line`` is the command line for the report's header."""

    def run(self, options: object, out: Path) -> int:
        """Measure and report into ``out`` (checked, created, swept); the exit code."""


def discover(package: str = STUDIES_PACKAGE) -> list[Study]:
    """The ``STUDY`` of every subpackage of ``package``, in name order; a subpackage without one is an error (a
    study folder that would silently not be a command)."""
    found = []
    for info in sorted(pkgutil.iter_modules(importlib.import_module(package).__path__), key=lambda m: m.name):
        if not info.ispkg:
            continue
        module = importlib.import_module(f"{package}.{info.name}")
        study = getattr(module, "STUDY", None)
        if not isinstance(study, Study):
            raise TypeError(f"{module.__name__}: a study folder must expose STUDY (name, help, add_arguments, "
                            f"options, run)")
        found.append(study)
    return found


def register(subparsers, study: Study) -> argparse.ArgumentParser:
    """``study`` as a subcommand of ``subparsers``; running it is ``run_study(study, args)``."""
    parser = subparsers.add_parser(study.name, help=study.help)
    study.add_arguments(parser)
    parser.set_defaults(func=functools.partial(run_study, study))
    return parser


def run_study(study: Study, args: argparse.Namespace) -> int:
    """Check every option value, then ``--out`` (bench and every study alike: empty, an existing file, a folder that
    cannot be made), then create it and remove our temps a killed earlier run left there; then measure."""
    options = study.options(args)
    out = output_dir(args.out, "--out")
    remove_abandoned_temps(out)
    package = stamp.package_of(inspect.getfile(type(study)))
    before, clock = stamp.everything(stamp.Files(stamp.CHECKOUT), package), Clock()  # the code this run loaded
    code = study.run(options, out)
    if code == 0:  # a failed run stamps nothing: its folder holds no complete results
        stamp.write(out, stamp.stamp(out, getattr(args, "command_line", "") or "", clock.started, clock.seconds,
                                     before, package))
    return code


def add_measurement_options(parser, out_help: str, suite_help: str) -> None:
    """The options every measuring command has: --out, --suite smoke|full (default full), --backend, --quiet."""
    parser.add_argument("--out", required=True, help=out_help)
    parser.add_argument("--suite", choices=NAMES, default="full", help=f"{suite_help} (default %(default)s)")
    add_backend_option(parser)
    parser.add_argument("--quiet", action="store_true", help="no progress bar")


def numbers_within(text: str | None, option: str, example: str, low: float, high: float, what: str = "degrees",
                   above_low: bool = False) -> list[float] | None:
    """A comma-separated option of numbers (``core.commands.comma_numbers``), each from ``low`` (or above it) to ``high``;
    else a UserError naming the option and the range."""
    from wgpuviewer.core.commands import comma_numbers
    from wgpuviewer.core.errors import UserError

    values = comma_numbers(text, option, example)
    if values is not None and not all((low < v if above_low else low <= v) and v <= high for v in values):
        span = f"above {low:g} and at most {high:g}" if above_low else f"from {low:g} to {high:g}"
        raise UserError(f"{option} {text!r}: expected {what} {span}")
    return values


class StudyCommand:
    """A study's command whose ``run`` module's ``run(out=OUT, **options)`` writes report.md: ``--out``, ``--suite``,
    ``--backend`` and ``--quiet`` (``add_measurement_options``) plus the study's own options (``add_options``), each
    checked by ``options`` (the shared ones by ``shared_options``)."""

    def __init__(self, name: str, help: str, out_help: str, suite_help: str):
        self.name, self.help, self.out_help, self.suite_help = name, help, out_help, suite_help

    def add_arguments(self, parser: argparse.ArgumentParser) -> None:
        add_measurement_options(parser, self.out_help, self.suite_help)
        self.add_options(parser)

    def add_options(self, parser: argparse.ArgumentParser) -> None:
        """The study's own options (none by default)."""

    @staticmethod
    def shared_options(args: argparse.Namespace) -> dict:
        """``run``'s keyword arguments from the options every measuring command has."""
        return {"suite_name": args.suite, "backend": args.backend, "progress": not args.quiet,
                "command": args.command_line}

    def options(self, args: argparse.Namespace) -> dict:
        return self.shared_options(args)

    def run(self, options: dict, out: Path) -> int:
        study = importlib.import_module(f"{type(self).__module__.rpartition('.')[0]}.run")
        study.run(out=out, **options)
        print(out / "report.md")
        return 0
