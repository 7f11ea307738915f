"""The WGSL composer: includes declared in the files, each file once, a line map back to the original files."""

from __future__ import annotations

from pathlib import Path

import pytest

import maptools
from wgpuviewer.core import wgsl
from wgpuviewer.core.wgsl import Generated, compose


@pytest.fixture
def files(monkeypatch):
    texts = {
        "a.wgsl": '// #include "c.wgsl"\nfn a() {}\n',
        "b.wgsl": '// #include "c.wgsl"\n// #include "a.wgsl"\nfn b() {\n  let x = ;\n}\n',
        "c.wgsl": "const C: f32 = 1.0;\n",
        "loop1.wgsl": '// #include "loop2.wgsl"\n',
        "loop2.wgsl": '// #include "loop1.wgsl"\n',
    }
    monkeypatch.setattr(wgsl, "read_wgsl", lambda name: texts[name])
    return texts


def test_each_file_once_after_what_it_includes(files):
    module = compose("b.wgsl", "a.wgsl")
    assert module.files == ("c.wgsl", "a.wgsl", "b.wgsl")
    assert module.code.count("const C") == 1
    assert "#include" not in module.code
    assert module.code.index("const C") < module.code.index("fn a") < module.code.index("fn b")


def test_line_map_names_the_original_file_and_line(files):
    module = compose(Generated("<generated: x>", "struct S { x: f32 }\n"), "b.wgsl")
    assert module.origin(1) == ("<generated: x>", 1)
    assert module.origin(2) == ("c.wgsl", 1)
    bad = module.code.splitlines().index("  let x = ;") + 1
    assert module.origin(bad) == ("b.wgsl", 4)
    message = f"Validation Error\n\nShader 'x' parsing error: expected expression\n  ┌─ wgsl:{bad}:11\n"
    assert module.locate(message) == "b.wgsl:4:11: parsing error: expected expression"
    assert module.locate("no location here") == "no location here"


def test_include_cycles_are_an_error(files):
    with pytest.raises(ValueError, match="loop1.wgsl -> loop2.wgsl -> loop1.wgsl"):
        compose("loop1.wgsl")


def test_every_shipped_file_composes_and_includes_only_shipped_files():
    """No file includes a missing one; every common/ file is used by something (the technique folders' files and the
    map kinds' kernels included)."""
    from wgpuviewer.techniques import TECHNIQUES

    root = wgsl.wgsl_dir()
    names = sorted(p.relative_to(root).as_posix() for p in root.rglob("*.wgsl"))
    names += sorted({t.wgsl_file for t in TECHNIQUES.values()})
    names += sorted(str(p) for p in Path(maptools.__file__).parent.rglob("*.wgsl"))  # the map kinds' kernels
    included = set()
    for name in names:
        module = compose(name)
        included.update(f for f in module.files if f != name)
    common = {n for n in names if n.startswith("common/")}
    assert common <= included, f"unused shared WGSL: {sorted(common - included)}"
