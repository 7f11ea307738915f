"""Stamps and freshness: a measuring command's run writes ``stamp.json`` (command, adapter, date, the fingerprint of
the parts its results use); a one-line change to a measured technique's WGSL makes its folder stale, and then
``wgpuviewer results --check`` exits 1 naming the folder until ``wgpuviewer docs`` writes the stale label beside
the numbers; the committed tree passes the check. All on temporary copies: the checkout is never written."""

from __future__ import annotations

import argparse
import shutil
from pathlib import Path

import pytest

from wgpuviewer.cli import main
from wgpuviewer.lab import docs, results
from wgpuviewer.lab.harness import stamp
from wgpuviewer.lab.harness.blocks import Block
from wgpuviewer.lab.harness.study import run_study

ROOT = Path(__file__).resolve().parents[2]
CODE = ("wgpuviewer/techniques", "wgsl", "maptools/kinds", "maptools/volume", "wgpuviewer/lab/bench")
PAGE = "docs/probe.md"


def test_the_committed_tree_passes_the_check(capsys):
    assert main(["results", "--check"]) == 0, capsys.readouterr().out


class FakeStudy:
    """A measuring command that writes what bench writes, without a GPU: a report header and a results file."""

    name, help = "fake", "a fake study"

    def add_arguments(self, parser):
        pass

    def options(self, args):
        return None

    def run(self, options, out: Path) -> int:
        (out / "report.md").write_text("# fake\n\n- command: `x`\n- adapter: **Fake adapter (CPU)**\n")
        (out / "results.csv").write_text("technique,params,p95\npom,layers=8,0.5\nbasic,-,0\n")
        return 0


def test_a_run_is_stamped_with_its_command_adapter_and_parts(tmp_path):
    out = tmp_path / "run"
    args = argparse.Namespace(out=str(out), command_line="wgpuviewer fake --out run")
    assert run_study(FakeStudy(), args) == 0
    record = stamp.read(out)
    assert record["command"] == "wgpuviewer fake --out run"
    assert record["adapter"] == "Fake adapter (CPU)"
    assert record["source"] == "run" and record["definition"] == stamp.DEFINITION
    parts = record["parts"]
    assert {"technique pom", "technique basic", "entry probe", "entry render", "code tests/lab"} <= set(parts)
    assert not any(p.startswith(("technique relief", "filter ")) for p in parts)  # only what its results use


@pytest.fixture
def checkout(tmp_path, monkeypatch) -> Path:
    """A copy of the measured code, a results folder stamped on it (pom, bench) and one page with its block."""
    for folder in CODE:
        shutil.copytree(ROOT / folder, tmp_path / folder, ignore=shutil.ignore_patterns("__pycache__"))
    run = tmp_path / "benchmarks" / "pom_run"
    run.mkdir(parents=True)
    (run / "results.csv").write_text("technique,p95\npom,0.25\n")
    parts = stamp.parts_for(stamp.Files(tmp_path), {"pom"}, (), "wgpuviewer/lab/bench")
    stamp.write(run, {"definition": stamp.DEFINITION, "source": "run", "command": "wgpuviewer bench", "adapter": "x",
                      "date": "2026-01-02T03:04:05Z", "seconds": 1.0,
                      "parts": stamp.fingerprint(stamp.Files(tmp_path), parts)})
    (tmp_path / "README.md").write_text("# a checkout\n")
    (tmp_path / "docs").mkdir()
    (tmp_path / PAGE).write_text(f"# probe\n\n{docs.BEGIN.format(name='pom p95')}\nold\n{docs.END}\n")
    block = Block(PAGE, "pom p95", "benchmarks/pom_run/results.csv",
                  lambda root: "p95: " + (root / "benchmarks/pom_run/results.csv").read_text().split()[-1],
                  results="benchmarks/pom_run")
    monkeypatch.setattr(docs, "BLOCKS", (block,))
    return tmp_path


def test_a_wgsl_change_makes_the_folder_stale_until_the_docs_say_so(checkout, capsys):
    root = str(checkout)
    assert main(["docs", "--root", root]) == 0
    assert main(["results", "--check", "--root", root]) == 0
    capsys.readouterr()
    assert main(["results", "--root", root]) == 0
    assert capsys.readouterr().out.startswith("benchmarks/pom_run: fresh")
    included = checkout / "wgsl" / "common" / "layer_march.wgsl"  # included by pom.wgsl: the composed search
    included.write_text(included.read_text() + "// one more line\n")
    assert main(["results", "--check", "--root", root]) == 1
    out = capsys.readouterr().out
    assert out.startswith("benchmarks/pom_run: stale: technique `pom` changed")
    assert main(["docs", "--root", root]) == 0  # the block now carries the stale label beside its number
    page = (checkout / PAGE).read_text()
    assert "*Measured on the code of 2026-01-02 (`benchmarks/pom_run/`); stale since: technique `pom` changed" in page
    assert "p95: pom,0.25" in page
    assert main(["results", "--check", "--root", root]) == 0


def test_a_folder_without_a_stamp_is_labelled_unknown(checkout):
    (checkout / "benchmarks" / "pom_run" / stamp.STAMP).unlink()
    state = results.freshness(checkout, "benchmarks/pom_run")
    assert not state.fresh and state.status() == "stale: fingerprint unknown (no stamp.json)"
    assert "has no stamp.json" in results.stale_note(checkout, "benchmarks/pom_run")


def test_a_changed_map_kernel_is_named(checkout):
    parts = stamp.parts_for(stamp.Files(checkout), {"distance"}, (), "wgpuviewer/lab/bench")
    assert "map distance" in parts and "map maxmip" in parts
    before = stamp.fingerprint(stamp.Files(checkout), parts)
    kernel = checkout / "maptools" / "volume" / "distance.wgsl"
    kernel.write_text(kernel.read_text() + "\n")
    after = stamp.fingerprint(stamp.Files(checkout), parts)
    assert [p for p in parts if before[p] != after[p]] == ["map distance"]


def test_a_stamp_of_another_definition_is_stale(checkout):
    folder = checkout / "benchmarks" / "pom_run"
    record = stamp.read(folder)
    stamp.write(folder, {**record, "definition": stamp.DEFINITION + 1, "parts": {"layers 32": "0"}})
    assert results.freshness(checkout, "benchmarks/pom_run").status() == "stale: the fingerprint's definition changed"


@pytest.mark.parametrize("entry", ["filter_probe", "shadow_probe", "gradient_probe"])
def test_a_changed_probe_entry_is_named(checkout, entry):
    """The filtering and shadow studies measure through these entry points: a change to one stales every folder."""
    parts = stamp.parts_for(stamp.Files(checkout), {"pom"}, ("ewa",), "wgpuviewer/lab/bench")
    before = stamp.fingerprint(stamp.Files(checkout), parts)
    source = checkout / "wgsl" / "entry" / f"{entry}.wgsl"
    source.write_text(source.read_text() + "// one more line\n")
    after = stamp.fingerprint(stamp.Files(checkout), parts)
    assert [p for p in parts if before[p] != after[p]] == [f"entry {entry}"]
