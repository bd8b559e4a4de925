"""The documented bounds and exit codes are the code's: the state format's bounds table
(docs/state-format.md) against mjtvm.model.bounds and the JSON Schema, and the exit-code
table (docs/cli.md) against mjtvm.cli.output."""

from __future__ import annotations

import json
import re
from importlib import resources
from pathlib import Path

from mjtvm.cli import output
from mjtvm.model import bounds

DOCS = Path(__file__).resolve().parents[2] / "docs"


def _table(page: str, heading: str) -> dict[str, list[str]]:
    """First cell -> the other cells of the table under ``## heading`` of ``page``."""
    text = (DOCS / page).read_text(encoding="utf-8")
    section = text.split(f"## {heading}\n", 1)[1].split("\n## ", 1)[0]
    rows = [line for line in section.splitlines() if line.startswith("|") and not line.startswith("|---")]
    cells = [[c.strip() for c in re.split(r"(?<!\\)\|", row)[1:-1]] for row in rows[1:]]
    return {c[0].strip("`"): c[1:] for c in cells}


def test_state_bounds_table_is_the_codes():
    table = _table("state-format.md", "Bounds")
    schema = json.loads(resources.files("mjtvm.data").joinpath("schema", "state.schema.json").read_text())
    assert table["every number"][0] == f"finite, \\|x\\| <= {bounds.MAX_ABS:.0e}".replace("e+", "e")
    assert table["friction_edges"][0] == (
        f"integer in [{bounds.MIN_FRICTION_EDGES}, {bounds.MAX_FRICTION_EDGES}]"
    )
    assert table["joints"][0] == f"1 to {bounds.MAX_JOINTS}"
    assert table["contacts"][0] == f"0 to {bounds.MAX_CONTACTS}"
    assert (
        table["refs`, `rvds"][0] == f"1 to {bounds.MAX_REFS} vectors each"
        and bounds.MAX_RVDS == bounds.MAX_REFS
    )
    assert table["operation-range vertices"][0] == f"3 to {bounds.MAX_RANGE_VERTICES}"
    assert table["names"][0].startswith(f"1 to {bounds.MAX_NAME} characters")
    assert table["nesting"][0] == f"{bounds.MAX_DEPTH} levels"
    assert table["file"][0] == f"{bounds.MAX_FILE_BYTES // 2**20} MiB"
    props = schema["properties"]
    assert props["joints"]["maxItems"] == bounds.MAX_JOINTS
    assert props["contacts"]["maxItems"] == bounds.MAX_CONTACTS
    assert props["friction_edges"]["minimum"] == bounds.MIN_FRICTION_EDGES
    assert props["friction_edges"]["maximum"] == bounds.MAX_FRICTION_EDGES


def test_exit_code_table_is_the_clis():
    table = _table("cli.md", "Exit codes")
    codes = {
        output.EXIT_OK, output.EXIT_FAILURE, output.EXIT_INPUT, output.EXIT_SOLVER,
        output.EXIT_INTERRUPTED, output.EXIT_PIPE,
    }  # fmt: skip  # a table: the CLI's exit codes
    assert {int(code) for code in table} == codes
