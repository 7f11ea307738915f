"""``wgpuviewer docs``: every generated block of README.md and docs/*.md is what its source makes (the committed
tree regenerates nothing), a tampered block is found by ``--check`` without a write and put back without ``--check``,
and a marker without a source or a source without its marker is an error."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from wgpuviewer.cli import main
from wgpuviewer.core.errors import UserError
from wgpuviewer.lab import docs

ROOT = Path(__file__).resolve().parents[2]


def test_every_block_of_the_committed_tree_is_up_to_date(capsys):
    """Regenerate them with `wgpuviewer docs`."""
    assert main(["docs", "--check"]) == 0, capsys.readouterr().out
    assert capsys.readouterr().out.strip() == "every generated block is up to date"


def test_every_block_has_its_marker_on_its_page():
    for block in docs.BLOCKS:
        assert (ROOT / block.page).read_text(encoding="utf-8").count(docs.BEGIN.format(name=block.name)) == 1, block


@pytest.fixture
def checkout(tmp_path) -> Path:
    """A copy of the checkout's pages, its committed results and its code (the results' freshness) linked in."""
    shutil.copy(ROOT / "README.md", tmp_path / "README.md")
    shutil.copytree(ROOT / "docs", tmp_path / "docs")
    for linked in ("benchmarks", "wgpuviewer", "wgsl", "maptools"):
        (tmp_path / linked).symlink_to(ROOT / linked)
    return tmp_path


def tamper(page: Path, name: str) -> None:
    text = page.read_text(encoding="utf-8")
    begin = docs.BEGIN.format(name=name)
    body = text.split(begin, 1)[1].split(docs.END, 1)[0]
    page.write_text(text.replace(body, body.replace("|", "/", 3), 1), encoding="utf-8")


def test_a_tampered_block_is_found_and_put_back(checkout, capsys):
    tamper(checkout / "README.md", "techniques")
    tamper(checkout / "docs" / "filtering.md", "filtering results")
    tampered = {p: p.read_text(encoding="utf-8") for p in (checkout / "README.md", checkout / "docs" / "filtering.md")}
    assert main(["docs", "--check", "--root", str(checkout)]) == 1
    out = capsys.readouterr().out.splitlines()
    assert out == ["README.md: block 'techniques' differs from the technique registry",
                   "docs/filtering.md: block 'filtering results' differs from "
                   "benchmarks/filtering_lavapipe/results.csv"]
    assert all(p.read_text(encoding="utf-8") == text for p, text in tampered.items())  # --check writes nothing
    assert main(["docs", "--root", str(checkout)]) == 0
    assert capsys.readouterr().out.splitlines() == [line.replace("differs from", "regenerated from") for line in out]
    assert (checkout / "README.md").read_text(encoding="utf-8") == (ROOT / "README.md").read_text(encoding="utf-8")
    assert (checkout / "docs" / "filtering.md").read_bytes() == (ROOT / "docs" / "filtering.md").read_bytes()
    assert not list(checkout.rglob(".*.tmp"))


def test_a_marker_without_a_source_is_an_error(checkout):
    page = checkout / "docs" / "maps.md"
    page.write_text(page.read_text(encoding="utf-8") + "\n<!-- generated: nothing -->\nx\n<!-- end generated -->\n")
    with pytest.raises(UserError, match="'nothing' has no source"):
        docs.run(checkout, check=True)


def test_a_source_without_its_marker_is_an_error(checkout):
    page = checkout / "docs" / "usage.md"
    page.write_text(page.read_text(encoding="utf-8").replace(docs.BEGIN.format(name="viewer keys"), ""))
    with pytest.raises(UserError, match="docs/usage.md: has no '<!-- generated: viewer keys -->' marker"):
        docs.run(checkout, check=False)


def test_a_root_without_a_readme_is_a_one_line_error(tmp_path, capsys):
    assert main(["docs", "--root", str(tmp_path)]) == 2
    assert "--root" in capsys.readouterr().err
