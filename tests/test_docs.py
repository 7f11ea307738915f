"""Every relative link in README.md, CHANGELOG.md and docs/*.md points at a file or folder of the checkout."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
PAGES = [ROOT / "README.md", ROOT / "CHANGELOG.md", *sorted((ROOT / "docs").glob("*.md"))]
#: [text](target) with the target up to a space, ')' or '#'; code spans are dropped first.
LINK = re.compile(r"\]\(([^)\s#]+)(?:#[^)\s]*)?\)")
#: <img src="target">: the README's screenshots.
IMG = re.compile(r'<img[^>]*\ssrc="([^"#]+)"')


def relative_links(page: Path) -> list[str]:
    text = re.sub(r"```.*?```|`[^`\n]*`", "", page.read_text(), flags=re.S)
    return [t for t in (*LINK.findall(text), *IMG.findall(text)) if not re.match(r"[a-z]+:", t)]


@pytest.mark.parametrize("page", PAGES, ids=lambda p: p.relative_to(ROOT).as_posix())
def test_relative_links_resolve(page):
    missing = [t for t in relative_links(page) if not (page.parent / t).exists()]
    assert not missing, f"{page.relative_to(ROOT)}: links to missing paths: {missing}"


def test_the_link_pattern_finds_links():
    assert LINK.findall("see [a](docs/x.md#part) and [`b`](b.md)") == ["docs/x.md", "b.md"]
    assert IMG.findall('<img src="docs/images/a.png" width="49%"> <img alt="b" src="b.png">') == [
        "docs/images/a.png", "b.png"]
