"""The measurement harness: the typed results table (round trip, clear errors), the report header, the suites,
study discovery, the plot context, and the order every measuring command runs in (``run_study``: options, then
the output folder, then the stale temps, then the measurement), on bench and every study alike."""

from __future__ import annotations

import argparse
import datetime
import importlib
import math
import os
import sys
import tempfile
import textwrap

import pytest

from wgpuviewer import cli
from wgpuviewer.core.errors import UserError
from wgpuviewer.lab.harness.header import Clock, Header
from wgpuviewer.lab.harness.study import Study, discover, run_study
from wgpuviewer.lab.harness.suite import Suite, pick, suites
from wgpuviewer.lab.harness.table import Column, Table

TABLE = Table("test results", (
    Column("name", str), Column("count", int, "rays"), Column("error", float, "texels"), Column("hit", bool),
    Column("late", float, optional=True, default=float("nan")),
))


def rows():
    return [
        {"name": "pom, 8 layers", "count": 4096, "error": 0.125, "hit": True, "late": 2.5},
        {"name": "quoted \"x\"", "count": None, "error": float("nan"), "hit": False, "late": float("inf")},
        {"name": "", "count": 0, "error": 1e-9, "hit": None, "late": None},
    ]


def test_table_round_trip_keeps_the_types(tmp_path):
    path = tmp_path / "out" / "results.csv"
    TABLE.write(path, rows())
    assert path.read_text().splitlines()[0] == "name,count,error,hit,late"
    back = TABLE.read(path)
    assert [list(r) for r in back] == [list(TABLE.names)] * 3
    first, second, third = back
    assert first == rows()[0] and type(first["count"]) is int and type(first["hit"]) is bool
    assert second["count"] is None and math.isnan(second["error"]) and second["late"] == math.inf
    assert second["name"] == 'quoted "x"' and second["hit"] is False
    assert third["error"] == 1e-9 and third["hit"] is None and third["late"] is None and third["name"] == ""
    assert not list(path.parent.glob(".*.tmp"))  # written atomically, nothing left behind


def test_a_blank_row_holds_no_values():
    assert TABLE.blank() == {"name": "", "count": None, "error": None, "hit": None, "late": None}


def test_floats_are_written_in_the_columns_format(tmp_path):
    table = Table("t", (Column("x", float), Column("y", float, format=".2f")))
    assert table.text([{"x": 1 / 3, "y": 1 / 3}]) == "x,y\n0.333333,0.33\n"


def test_an_optional_column_missing_from_an_older_file_reads_as_its_default(tmp_path):
    path = tmp_path / "old.csv"
    path.write_text("name,count,error,hit\na,1,2,True\n")
    (row,) = TABLE.read(path)
    assert row["count"] == 1 and row["error"] == 2.0 and math.isnan(row["late"])


@pytest.mark.parametrize("text, fragments", [
    ("name,count,error,hit,late,extra\n", ["unknown column(s) 'extra'", "test results"]),
    ("name,count,hit\n", ["no column(s) 'error'"]),
    ("name,count,error,hit\na,1.5,2,True\n", ["line 2", "'count'", "'1.5'", "whole number"]),
    ("name,count,error,hit\na,1,lots,True\n", ["line 2", "'error'", "'lots'", "a number"]),
    ("name,count,error,hit\na,1,2,yes\n", ["'hit'", "True or False"]),
    ("name,count,error,hit\na,1,2\n", ["line 2", "3 cells", "header has 4"]),
    ("", ["empty"]),
])
def test_a_file_that_is_not_the_table_is_a_one_line_error_naming_it(tmp_path, text, fragments):
    path = tmp_path / "bad.csv"
    path.write_text(text)
    with pytest.raises(UserError) as error:
        TABLE.read(path)
    message = str(error.value)
    assert message.startswith(str(path)) and "\n" not in message
    for fragment in fragments:
        assert fragment in message, message


def test_a_missing_file_is_a_user_error(tmp_path):
    with pytest.raises(UserError, match="cannot read test results"):
        TABLE.read(tmp_path / "nope.csv")


def test_writing_a_value_of_the_wrong_type_or_a_row_without_a_column_fails():
    with pytest.raises(ValueError, match="'count'"):
        TABLE.text([{**rows()[0], "count": 2.5}])
    with pytest.raises(ValueError, match="'hit'"):
        TABLE.text([{**rows()[0], "hit": "maybe"}])
    with pytest.raises(ValueError, match="late"):
        TABLE.text([{k: v for k, v in rows()[0].items() if k != "late"}])
    with pytest.raises(TypeError):
        Column("x", list)
    with pytest.raises(ValueError, match="twice"):
        Table("t", (Column("x"), Column("x")))


def test_header_fields():
    started = datetime.datetime(2026, 1, 2, 3, 4, tzinfo=datetime.UTC)
    header = Header("A study", "wgpuviewer study --out 'a b'", "llvmpipe (CPU) via Vulkan", "smoke", started, 41.6)
    assert header.lines() == ["# A study", "", "- command: `wgpuviewer study --out 'a b'`",
                              "- adapter: **llvmpipe (CPU) via Vulkan**", "- suite: `smoke`",
                              "- date: 2026-01-02 03:04 UTC", "- duration: 42 s"]
    again = Header("A study", "wgpuviewer bench --from-csv a.csv", "GPU", "full", None, None, ("a.csv", "b.csv"))
    assert "- date: not recorded in the results; report regenerated from a.csv, b.csv" in again.lines()
    assert "- duration: –" in again.lines()
    made = Clock().header("T", "c", "a", "full")
    assert made.seconds >= 0 and made.started.tzinfo is datetime.UTC


def test_suites_are_exactly_smoke_and_full():
    table = suites(Suite("smoke"), Suite("full"))
    assert pick(table, "smoke") is table["smoke"]
    with pytest.raises(UserError, match="--suite 'huge': unknown; expected one of smoke, full"):
        pick(table, "huge")
    for wrong in ((Suite("smoke"),), (Suite("smoke"), Suite("full"), Suite("full")), (Suite("smoke"), Suite("big"))):
        with pytest.raises(ValueError):
            suites(*wrong)


def _package(root, name: str, studies: dict[str, str]) -> None:
    folder = root / name
    folder.mkdir()
    (folder / "__init__.py").write_text('"""Test studies."""\n')
    (folder / "helpers.py").write_text("X = 1\n")  # a module, not a study folder
    for sub, body in studies.items():
        (folder / sub).mkdir()
        (folder / sub / "__init__.py").write_text(textwrap.dedent(body))


STUDY_BODY = '''
class _Study:
    name = "{name}"
    help = "a test study"

    def add_arguments(self, parser):
        parser.add_argument("--out")

    def options(self, args):
        return args

    def run(self, options, out):
        return 0


STUDY = _Study()
'''


def test_discovery_finds_every_study_folder_and_refuses_one_without_a_study(tmp_path, monkeypatch):
    monkeypatch.syspath_prepend(str(tmp_path))
    _package(tmp_path, "hd_studies_ok", {"zeta": STUDY_BODY.format(name="zeta"),
                                         "alpha_beta": STUDY_BODY.format(name="alpha-beta")})
    found = discover("hd_studies_ok")
    assert [s.name for s in found] == ["alpha-beta", "zeta"] and all(isinstance(s, Study) for s in found)
    _package(tmp_path, "hd_studies_bad", {"good": STUDY_BODY.format(name="good"), "lost": '"""No STUDY here."""\n'})
    with pytest.raises(TypeError, match="hd_studies_bad.lost: a study folder must expose STUDY"):
        discover("hd_studies_bad")
    for name in [m for m in sys.modules if m.startswith("hd_studies_")]:
        monkeypatch.delitem(sys.modules, name)


def test_plot_context_saves_pngs_atomically(tmp_path):
    from wgpuviewer.lab.harness.plots import pyplot, save_png

    with pyplot() as plt:
        if plt is None:
            pytest.skip("matplotlib is not installed")
        import matplotlib

        assert matplotlib.get_backend().lower() == "agg"
        fig, ax = plt.subplots()
        ax.plot([0, 1], [1, 0])
        assert save_png(fig, tmp_path / "p" / "a.png") == "a.png"
        assert not plt.get_fignums()  # saved figures are closed
    assert (tmp_path / "p" / "a.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert not list((tmp_path / "p").glob(".*.tmp"))


# --- the order every measuring command runs in -------------------------------------------------------------------

#: bench and every study: what ``wgpuviewer`` registers as measuring commands.
COMMANDS = {study.name: study for study in cli.measurement_commands()}


@pytest.fixture
def measured(monkeypatch):
    """Every measuring command's measurement (its ``run`` module's ``run``) replaced by a record of its calls: the
    GPU never starts, so a test sees only what happens before it."""
    calls = []
    for name, study in COMMANDS.items():
        module = importlib.import_module(type(study).__module__.rpartition(".")[0] + ".run")
        monkeypatch.setattr(module, "run", lambda *args, name=name, **kwargs: calls.append(name) or [])
    return calls


def one_line(capsys) -> str:
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("wgpuviewer: error: "), lines
    return lines[0].removeprefix("wgpuviewer: error: ")


def _bad_out(kind: str, root) -> tuple[str, str]:
    """An --out value of ``kind`` under ``root`` and the error every command gives for it."""
    if kind == "empty":
        return "", "--out '': empty; give a folder path"
    if kind == "file":
        (root / "file").write_text("x")
        return str(root / "file"), f"--out {root / 'file'}: exists and is not a folder; give a folder path"
    if kind == "dangling link":
        (root / "link").symlink_to(root / "gone")
        return str(root / "link"), f"--out {root / 'link'}: exists and is not a folder; give a folder path"
    if kind == "under a file":
        (root / "file").write_text("x")
        return str(root / "file" / "sub"), (f"--out {root / 'file' / 'sub'}: cannot write there (Not a directory); "
                                            f"a part of the path is a file, not a folder; choose another path")
    long = root / "new" / ("x" * 300)
    return str(long), f"--out {long}: cannot write there (File name too long); the name is too long; choose a " \
                      f"shorter path"


@pytest.mark.parametrize("kind", ["empty", "file", "dangling link", "under a file", "name too long"])
@pytest.mark.parametrize("command", list(COMMANDS))
def test_every_command_refuses_a_bad_out_alike_before_anything(tmp_path, monkeypatch, measured, capsys, command,
                                                                 kind):
    monkeypatch.chdir(tmp_path)  # an empty --out must not mean the current folder
    out, message = _bad_out(kind, tmp_path)
    before = sorted(os.listdir(tmp_path))
    assert cli.main([command, "--out", out, "--suite", "smoke", "--quiet"]) == 2
    assert one_line(capsys) == message
    assert sorted(os.listdir(tmp_path)) == before and measured == []  # nothing made, nothing measured


@pytest.mark.parametrize("argv, fragment", [
    (["refined-distance", "--heightmaps", "bricks,bogus"], "--heightmaps: unknown height map 'bogus'"),
    (["refined-distance", "--angles", "90"], "--angles '90'"),
    (["bench", "--heightmaps", "bogus"], "--heightmaps: unknown height map 'bogus'"),
    (["bench", "--from-csv", "missing.csv"], "--from-csv missing.csv: no such file"),
    (["filtering", "--reliefs", "lava"], "--reliefs: unknown relief 'lava'"),
])
def test_option_values_are_checked_before_the_output_folder_is_made(tmp_path, monkeypatch, measured, capsys, argv,
                                                                    fragment):
    monkeypatch.chdir(tmp_path)
    assert cli.main([argv[0], "--out", "new", "--suite", "smoke", *argv[1:]]) == 2
    assert fragment in one_line(capsys)
    assert not (tmp_path / "new").exists() and measured == []


def _our_temp(folder, name: str) -> str:
    """A temp file as core.io.atomic_open names it, left as by a killed writer (unlocked)."""
    fd, path = tempfile.mkstemp(prefix=f".{name}.", suffix=".tmp", dir=folder)
    os.write(fd, b"partial")
    os.close(fd)
    return os.path.basename(path)


@pytest.mark.parametrize("command", list(COMMANDS))
def test_a_run_sweeps_the_temps_a_killed_run_left_and_nothing_else(tmp_path, measured, command):
    out = tmp_path / "out"
    out.mkdir()
    stale = [_our_temp(out, "error_along_span.png"), _our_temp(out, "results.csv")]
    kept = [".notes.tmp", "draft.tmp", ".results.csv.mine.tmp", ".results.csv.ABCDEFGH.tmp", "results.csv"]
    for name in kept:
        (out / name).write_text("the user's")
    assert cli.main([command, "--out", str(out), "--suite", "smoke", "--quiet"]) == 0
    assert measured == [command]
    kept.append("stamp.json")  # what the finished run adds: its stamp (harness.stamp)
    assert sorted(os.listdir(out)) == sorted(kept) and not any((out / name).exists() for name in stale)


def test_run_study_checks_the_options_first_and_hands_the_measurement_a_made_folder(tmp_path):
    seen = []

    class Probe:
        name, help = "probe", "records what it is given"

        def add_arguments(self, parser):
            pass

        def options(self, args):
            if args.bad:
                raise UserError("--bad: refused")
            return {"checked": True}

        def run(self, options, out):
            seen.append((options, out, out.is_dir()))
            return 0

    out = tmp_path / "a" / "b"
    with pytest.raises(UserError, match="--bad"):
        run_study(Probe(), argparse.Namespace(out=str(out), bad=True))
    assert not (tmp_path / "a").exists() and seen == []
    assert run_study(Probe(), argparse.Namespace(out=str(out), bad=False)) == 0
    assert seen == [({"checked": True}, out, True)]
