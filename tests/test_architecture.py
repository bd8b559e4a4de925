"""The house rules of docs/architecture.md, read from the source: no import cycle between
modules, no private name imported from another module, no module over 450 lines, a short
public API, and the architecture page's rooms in the order of the import-linter contract."""

from __future__ import annotations

import ast
import re
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "mjtvm"
MAX_LINES = 450
MAX_EXPORTS = 150  # names in the __all__ of the __init__s, summed (docs/architecture.md)


def _name(path: Path) -> str:
    parts = path.relative_to(ROOT).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


MODULES = {_name(p): p for p in PACKAGE.rglob("*.py")}


def _absolute(module: str, node: ast.ImportFrom) -> str:
    if node.level == 0:
        return node.module or ""
    package = module if MODULES[module].name == "__init__.py" else module.rsplit(".", 1)[0]
    base = package.split(".")[: len(package.split(".")) - node.level + 1]
    return ".".join(base + ([node.module] if node.module else []))


def _imports() -> dict[str, list[tuple[str, str, int]]]:
    """``{module: [(imported module, name or '', line), ...]}`` inside the package, every import
    (in functions and under ``TYPE_CHECKING`` too)."""
    out: dict[str, list[tuple[str, str, int]]] = {}
    for module, path in MODULES.items():
        found = out.setdefault(module, [])
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Import):
                found += [(a.name, "", node.lineno) for a in node.names if a.name in MODULES]
            elif isinstance(node, ast.ImportFrom):
                target = _absolute(module, node)
                for a in node.names:
                    if f"{target}.{a.name}" in MODULES:  # a module imported from its package
                        found.append((f"{target}.{a.name}", "", node.lineno))
                    elif target in MODULES:
                        found.append((target, a.name, node.lineno))
    return out


def _cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of more than one module (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    found: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in graph[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                found.append(sorted(component))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return found


def test_no_import_cycle_between_modules() -> None:
    # a package's __init__ importing its own modules is not a cycle through them
    graph = {
        m: {
            t
            for t, _, _ in targets
            if t != m and not (m.startswith(f"{t}.") and MODULES[t].name == "__init__.py")
        }
        for m, targets in _imports().items()
    }
    assert _cycles(graph) == []


def test_no_private_name_imported_from_another_module() -> None:
    private = [
        f"{m}:{line} imports {name} from {target}"
        for m, targets in _imports().items()
        for target, name, line in targets
        if name.startswith("_") and not name.startswith("__")
    ]
    assert private == []


def test_no_module_over_450_lines() -> None:
    long = {
        m: n for m, p in MODULES.items() if (n := len(p.read_text(encoding="utf-8").splitlines())) > MAX_LINES
    }
    assert long == {}


def _exports() -> dict[str, int]:
    counts = {}
    for module, path in MODULES.items():
        if path.name != "__init__.py":
            continue
        for node in ast.parse(path.read_text(encoding="utf-8")).body:
            if isinstance(node, ast.Assign) and any(getattr(t, "id", "") == "__all__" for t in node.targets):
                counts[module] = len(node.value.elts)  # type: ignore[attr-defined]
    return counts


def test_the_public_api_is_short_and_the_page_states_its_size() -> None:
    total = sum(_exports().values())
    assert total <= MAX_EXPORTS
    page = (ROOT / "docs" / "architecture.md").read_text(encoding="utf-8")
    assert f"{total} names" in page


def test_the_architecture_page_lists_the_rooms_of_the_layers_contract() -> None:
    config = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))
    contract = next(c for c in config["tool"]["importlinter"]["contracts"] if c["name"].startswith("Rooms:"))
    page = (ROOT / "docs" / "architecture.md").read_text(encoding="utf-8")
    table = re.findall(r"^\| `(mjtvm[\w.]*)` \|", page.split("## Rooms", 1)[1], re.M)
    assert table == contract["layers"]
    rooms = {
        m
        for m, p in MODULES.items()
        if m.count(".") == 1 and (p.name == "__init__.py" or m == "mjtvm.errors")
    }
    assert rooms - {"mjtvm.data"} == set(table)
