"""The measurement harness: the typed results table (round trip, clear errors), the report header, the suites,
study discovery and the plot context."""

from __future__ import annotations

import datetime
import math
import sys
import textwrap

import pytest

from wgpuviewer.core.errors import UserError
from wgpuviewer.harness.header import Clock, Header
from wgpuviewer.harness.study import Study, discover
from wgpuviewer.harness.suite import Suite, pick, suites
from wgpuviewer.harness.table import Column, Table

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

    def run(self, args):
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
    from wgpuviewer.harness.plots import pyplot, save_png

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
