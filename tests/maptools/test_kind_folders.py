"""A map kind is one folder (``maptools/kinds/KIND/``), found without a list: its entry, its docstring's import rule,
its kernels beside it, and its texture slots in the renderer's one table."""

from __future__ import annotations

import importlib
from pathlib import Path

from maptools import kinds
from maptools.registry import KINDS
from wgpuviewer.relief.maps import MAP_SLOTS

FOLDERS = sorted(p.name for p in Path(kinds.__file__).parent.iterdir() if (p / "__init__.py").is_file())


def test_every_folder_is_a_kind_and_every_kind_a_folder():
    assert sorted(KINDS) == FOLDERS
    assert [k.order for k in KINDS.values()] == sorted(k.order for k in KINDS.values())


def test_each_folder_says_what_lives_there_and_what_it_may_import():
    for name in FOLDERS:
        doc = importlib.import_module(f"maptools.kinds.{name}").__doc__ or ""
        assert "May import" in doc and f"``{name}``" in doc, name


def test_each_kernel_is_a_wgsl_file_of_the_package():
    root = Path(kinds.__file__).parents[1]
    for kind in KINDS.values():
        for kernel in kind.kernels:
            assert kernel.path.is_file() and root in kernel.path.parents, (kind.name, kernel)


def test_each_kind_slot_is_in_the_renderers_table():
    for name in FOLDERS:
        path = Path(kinds.__file__).parent / name / "slot.py"
        if path.is_file():
            for slot in importlib.import_module(f"maptools.kinds.{name}.slot").SLOTS:
                assert MAP_SLOTS[slot.name] is slot
