"""The rooms and their rules (docs/architecture.md): who may import whom, no import cycles, a docstring per room,
the keys table of docs/usage.md and the README's technique, filter and map-kind tables generated from their one
source."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

from maptools import registry as map_registry
from wgpuviewer import techniques
from wgpuviewer.relief import filters
from wgpuviewer.viewer.keys import markdown_table

ROOT = Path(__file__).resolve().parents[1]


def module_name(path: Path) -> str:
    parts = list(path.relative_to(ROOT).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts = parts[:-1]
    return ".".join(parts)


def project_modules() -> dict[str, Path]:
    files = [*(ROOT / "wgpuviewer").rglob("*.py"), *(ROOT / "maptools").rglob("*.py")]
    return {module_name(f): f for f in files}


def imports_of(name: str, path: Path, known: set[str]) -> set[str]:
    """Project modules ``name`` imports anywhere in the file (function-level imports included)."""
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    found = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            targets = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                anchor = package.split(".")[: len(package.split(".")) - node.level + 1]
                base = ".".join(anchor + ([base] if base else []))
            # `from package import module` depends on the module; `from module import name` on the module.
            targets = [f"{base}.{a.name}" if f"{base}.{a.name}" in known else base for a in node.names]
        else:
            continue
        for target in targets:
            while target and target not in known:
                target = target.rpartition(".")[0]
            if target and target != name:
                found.add(target)
    return found


def graph() -> dict[str, set[str]]:
    modules = project_modules()
    known = set(modules)
    return {name: imports_of(name, path, known) for name, path in modules.items()}


#: What each room may import (docs/architecture.md, "The rooms"). A folder room (one technique, one map kind, one
#: study) is its kind plus its folder name: it never imports another folder of its kind, only the shared modules
#: around them ("techniques", "maptools", "harness").
PRODUCT = {"core", "maptools", "map kind", "techniques", "technique", "scene", "relief", "viewer", "api", "export"}
RULES = {
    "core": set(),
    "maptools": {"core", "map kind"},  # the registry finds the kinds; the CLI, cache and check use them
    "map kind": {"core", "maptools"},
    "techniques": {"core"},  # the registry: types and discovery (folders are found at run time, never imported)
    "technique": {"core", "techniques", "maptools", "map kind", "relief"},  # auto's table runs the probe
    "scene": {"core", "techniques", "scene"},
    "relief": {"core", "maptools", "map kind", "techniques", "scene"},
    "viewer": {"core", "maptools", "map kind", "techniques", "scene", "relief"},
    "api": {"core", "techniques", "scene", "relief", "viewer"},
    "export": {"core", "techniques", "relief", "maptools"},  # a technique's module for other renderers, its maps
    "harness": {"core"},
    "bench": PRODUCT | {"harness"},
    "study": PRODUCT | {"harness", "bench"},
    "lab": PRODUCT | {"harness", "bench", "study"},  # the GPU suite and the docs command
}


def room(name: str) -> tuple[str, str]:
    """(room, folder) of a module: folder is the technique, map kind or study it belongs to, else ""."""
    parts = name.split(".")
    if parts[0] == "maptools":
        return ("map kind", parts[2]) if len(parts) >= 3 and parts[1] == "kinds" else ("maptools", "")
    top = parts[1] if len(parts) >= 2 else ""
    if top == "lab":
        sub = parts[2] if len(parts) >= 3 else ""
        if sub == "studies" and len(parts) >= 4:
            return "study", parts[3]
        return (sub, "") if sub in ("bench", "harness") else ("lab", "")
    if top == "techniques":
        folder = parts[2] if len(parts) >= 3 and (ROOT / "wgpuviewer" / "techniques" / parts[2]).is_dir() else ""
        return ("technique", folder) if folder else ("techniques", "")
    if top in ("scene", "textures", "meshes", "camera"):
        return "scene", ""
    if top in ("core", "relief", "viewer", "api", "export"):
        return top, ""
    return "front", ""  # the package itself, cli, __main__ and the documented re-exports: anything


def allowed(src: str, dst: str) -> bool:
    (a, folder_a), (b, folder_b) = room(src), room(dst)
    if a == "front" or dst in ("wgpuviewer", "wgpuviewer.lab.studies"):
        return True
    if a == b:
        return folder_a == folder_b or not folder_b
    return b in RULES[a]


def test_rooms_import_only_what_they_may():
    bad = sorted(f"{src} -> {dst}" for src, dsts in graph().items() for dst in dsts if not allowed(src, dst))
    assert not bad, "imports against the rules of docs/architecture.md:\n" + "\n".join(bad)


def test_the_product_never_imports_the_lab():
    lab = {"lab", "harness", "bench", "study"}
    bad = sorted(f"{src} -> {dst}" for src, dsts in graph().items() if room(src)[0] in PRODUCT
                 for dst in dsts if room(dst)[0] in lab)
    assert not bad, "the product imports the lab:\n" + "\n".join(bad)


#: Size limits of the project's Python: a module longer than this does several jobs; a function longer than this
#: does several steps that want names.
MAX_MODULE_LINES = 500
MAX_FUNCTION_LINES = 80


def test_modules_and_functions_stay_small():
    too_long = []
    for path in project_modules().values():
        text = path.read_text()
        if text.count("\n") > MAX_MODULE_LINES:
            too_long.append(f"{path.relative_to(ROOT)}: {text.count(chr(10))} lines (at most {MAX_MODULE_LINES})")
        for node in ast.walk(ast.parse(text)):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                lines = node.end_lineno - node.lineno + 1
                if lines > MAX_FUNCTION_LINES:
                    too_long.append(f"{path.relative_to(ROOT)}:{node.lineno} {node.name}: {lines} lines "
                                    f"(at most {MAX_FUNCTION_LINES})")
    assert not too_long, "\n".join(too_long)


def test_no_import_cycles():
    g = graph()
    state: dict[str, int] = {}
    cycles = []

    def visit(node, stack):
        state[node] = 1
        for nxt in sorted(g[node]):
            if state.get(nxt) == 1:
                cycles.append(" -> ".join(stack[stack.index(nxt):] + [nxt]))
            elif nxt not in state:
                visit(nxt, stack + [nxt])
        state[node] = 2

    for node in sorted(g):
        if node not in state:
            visit(node, [node])
    assert not cycles, "\n".join(cycles)


def test_every_room_says_what_lives_there_and_what_it_may_import():
    for init in [*(ROOT / "wgpuviewer").rglob("__init__.py"), ROOT / "maptools" / "__init__.py"]:
        if init.parent.name == "wgsl":
            continue
        doc = ast.get_docstring(ast.parse(init.read_text())) or ""
        assert "import" in doc, f"{init.relative_to(ROOT)}: the docstring must say what the room may import"


def test_usage_keys_table_is_the_key_table():
    assert markdown_table() in (ROOT / "docs" / "usage.md").read_text()


def generated_section(text: str, name: str) -> str:
    """The README's text between `<!-- generated: NAME -->` and the next `<!-- end generated -->`."""
    begin = f"<!-- generated: {name} -->"
    assert text.count(begin) == 1, f"README.md needs exactly one {begin!r} marker"
    return text.split(begin, 1)[1].split("<!-- end generated -->", 1)[0].strip()


@pytest.mark.parametrize("name, table", [("techniques", techniques.markdown_table), ("filters", filters.markdown_table),
                                         ("map kinds", map_registry.markdown_table)])
def test_readme_registry_tables_are_generated(name, table):
    """The README's technique, filter and map-kind tables are exactly what the registries generate (regenerate them
    with e.g. `python -c "from wgpuviewer.techniques import markdown_table; print(markdown_table())"`)."""
    assert generated_section((ROOT / "README.md").read_text(), name) == table().strip()
