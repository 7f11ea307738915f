"""A study as a ``wgpuviewer`` subcommand: the ``Study`` protocol every study folder exposes as ``STUDY`` (in its
``__init__``), its discovery (every package under ``wgpuviewer.lab.studies``), its registration on the command line
with the options every measuring command shares (the CLI puts the command line, ``core.cli.command_line``, on
``args.command_line`` for the report's header), and ``run_study``, the one order every measuring command runs in:
every option value checked, then the output folder checked and created and the stale temps of a killed earlier
run swept from it, then the measurement (the GPU starts only there).

A study's ``__init__`` stays light (no GPU, no heavy imports): the command line imports every study to build
its parser; ``options`` and ``run`` import the measuring code when the command runs.
"""

from __future__ import annotations

import argparse
import functools
import importlib
import pkgutil
from pathlib import Path
from typing import Protocol, runtime_checkable

from wgpuviewer.core.cli import add_backend_option
from wgpuviewer.core.io import output_dir, remove_abandoned_temps

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
    return study.run(options, out)


def add_measurement_options(parser, out_help: str, suite_help: str) -> None:
    """The options every measuring command has: --out, --suite smoke|full (default full), --backend, --quiet."""
    parser.add_argument("--out", required=True, help=out_help)
    parser.add_argument("--suite", choices=NAMES, default="full", help=f"{suite_help} (default %(default)s)")
    add_backend_option(parser)
    parser.add_argument("--quiet", action="store_true", help="no progress bar")
