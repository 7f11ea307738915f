"""A study as a ``wgpuviewer`` subcommand: the ``Study`` protocol every study folder exposes as ``STUDY`` (in its
``__init__``), its discovery (every package under ``wgpuviewer.studies``), its registration on the command line
with the options every measuring command shares (the CLI puts the command line, ``core.cli.command_line``, on
``args.command_line`` for the report's header).

A study's ``__init__`` stays light (no GPU, no heavy imports): the command line imports every study to build
its parser; ``run`` imports the measuring code when the command runs.
"""

from __future__ import annotations

import argparse
import importlib
import pkgutil
from typing import Protocol, runtime_checkable

from wgpuviewer.core.cli import add_backend_option

from .suite import NAMES

STUDIES_PACKAGE = "wgpuviewer.studies"


@runtime_checkable
class Study(Protocol):
    name: str  # the subcommand, e.g. "refined-distance"
    help: str  # one line for ``wgpuviewer --help``

    def add_arguments(self, parser: argparse.ArgumentParser) -> None:
        """The command's own options (``add_measurement_options`` adds the shared ones)."""

    def run(self, args: argparse.Namespace) -> int:
        """Measure and report; the exit code. ``args.command_line`` is the command line for the report's header."""


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
            raise TypeError(f"{module.__name__}: a study folder must expose STUDY (name, help, add_arguments, run)")
        found.append(study)
    return found


def register(subparsers, study: Study) -> argparse.ArgumentParser:
    """``study`` as a subcommand of ``subparsers``; running it calls ``study.run(args)``."""
    parser = subparsers.add_parser(study.name, help=study.help)
    study.add_arguments(parser)
    parser.set_defaults(func=study.run)
    return parser


def add_measurement_options(parser, out_help: str, suite_help: str) -> None:
    """The options every measuring command has: --out, --suite smoke|full (default full), --backend, --quiet."""
    parser.add_argument("--out", required=True, help=out_help)
    parser.add_argument("--suite", choices=NAMES, default="full", help=suite_help)
    add_backend_option(parser)
    parser.add_argument("--quiet", action="store_true", help="no progress bar")
