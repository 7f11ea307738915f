"""Both command lines document themselves: every subcommand, positional and option has a help text, every default
is in it, and `--version` gives the installed distribution's version."""

from __future__ import annotations

import argparse
from importlib.metadata import version

import pytest

from maptools import VERSION
from maptools import cli as maptools_cli
from wgpuviewer import cli


def _parsers():
    yield "wgpuviewer", cli.build_parser()[0]
    yield "maptools", maptools_cli.build_parser()


def _actions(parser: argparse.ArgumentParser, path: str):
    """(command path, action) of every argument of ``parser`` and its subcommands, and (path, None, subcommand
    help) for each subcommand."""
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            helps = {choice.dest: choice.help for choice in action._choices_actions}
            for name, sub in action.choices.items():
                yield f"{path} {name}", None, helps.get(name)
                yield from _actions(sub, f"{path} {name}")
        elif not isinstance(action, (argparse._HelpAction, argparse._VersionAction)):
            yield path, action, action.help


def _every_argument():
    return [(path, action, text) for prog, parser in _parsers() for path, action, text in _actions(parser, prog)]


def test_every_subcommand_positional_and_option_has_a_help_text():
    missing = [f"{path} {'/'.join(action.option_strings) or action.dest if action else '(the subcommand)'}"
               for path, action, text in _every_argument() if not (text and text.strip())]
    assert not missing, missing


def test_every_default_is_in_its_help_text():
    """An option whose value is used when it is not given says what that value is (argparse's %(default)s)."""
    hidden = []
    for path, action, text in _every_argument():
        if action is None or action.default in (None, False, argparse.SUPPRESS) or action.nargs == 0:
            continue
        if "default" not in (text or "").lower():
            hidden.append(f"{path} {'/'.join(action.option_strings)} (default {action.default!r})")
    assert not hidden, hidden


def test_batch_help_documents_its_inputs_output_and_jobs(capsys):
    assert maptools_cli.main(["batch", "--help"]) == 0
    text = " ".join(capsys.readouterr().out.split())
    assert "INPUT [INPUT ...]" in text and "height map files (8/16-bit PNG, JPEG, TIFF, EXR" in text
    assert "-o DIR, --output DIR output folder (created if missing)" in text
    assert "--jobs JOBS worker threads reading and writing files (default 1;" in text


@pytest.mark.parametrize("prog,main", [("wgpuviewer", cli.main), ("maptools", maptools_cli.main)])
def test_version_comes_from_the_package_metadata(prog, main, capsys):
    assert main(["--version"]) == 0
    out = capsys.readouterr().out.strip()
    assert out.startswith(f"{prog} {version('wgpuviewer')}")
    if prog == "maptools":
        assert out.endswith(f"CPU references {VERSION})")
