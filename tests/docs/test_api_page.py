"""docs/api.md lists exactly the public names (each room's ``__all__``), docs/internals.md the rest:
both equal what ``tools/api_page.py`` writes from the package's source."""

from __future__ import annotations

import importlib
import importlib.util
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def _tool():
    spec = importlib.util.spec_from_file_location("api_page", ROOT / "tools" / "api_page.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_api_and_internals_pages_are_the_generated_ones() -> None:
    tool = _tool()
    assert (ROOT / "docs" / "api.md").read_text(encoding="utf-8") == tool.api_page()
    assert (ROOT / "docs" / "internals.md").read_text(encoding="utf-8") == tool.internals_page()


def test_the_api_page_renders_each_public_name_once_and_nothing_else() -> None:
    rooms = _tool().rooms()
    blocks = re.findall(r"^::: (\S+)$", (ROOT / "docs" / "api.md").read_text(encoding="utf-8"), re.M)
    rendered = [b for b in blocks if b not in {room for room, _, _ in rooms}]  # a room: its docstring
    assert len(rendered) == len(set(rendered))
    public = set()
    for room, _, names in rooms:
        package = importlib.import_module(room)
        for name, module in names:
            # each listed name is what the room exports, and the page's object is that object
            assert getattr(package, name) is getattr(importlib.import_module(module), name), (room, name)
            public.add(f"{module}.{name}")
    assert set(rendered) == public
    internals = (ROOT / "docs" / "internals.md").read_text(encoding="utf-8")
    for ident in public:
        module, name = ident.rsplit(".", 1)
        block = re.search(rf"^::: {re.escape(module)}\n    options:\n      members: (.*)$", internals, re.M)
        assert block is None or name not in re.findall(r"\w+", block.group(1)), ident
