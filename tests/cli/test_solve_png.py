"""``mjtvm solve --png FILE`` and ``mjtvm tvms --png FILE``, as a user runs them: the picture is
written, standard output stays the JSON document alone (``| python -m json.tool``), the
``wrote`` line goes to stderr, a bad path is one line naming ``--png`` (exit 2), and without
``--png`` matplotlib is not imported."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from tests.cli.test_cli import _console_script

PNG = b"\x89PNG\r\n\x1a\n"


def _run(*words: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([*_console_script(), *words], capture_output=True, text=True, check=False)


@pytest.mark.parametrize(
    ("words", "schema"),
    [
        (["solve", "case2"], "mjtvm.result/1"),
        (["solve", "case2", "--mg", "100"], "mjtvm.result/1"),  # no solution: a picture with a note
        (["solve"], "mjtvm.result/1"),  # the shipped pinch.json state file
        (["tvms", "case2", "--quiet"], "mjtvm.tvms/1"),
    ],
)
def test_png_is_written_and_stdout_stays_json(words: list[str], schema: str, tmp_path: Path) -> None:
    png = tmp_path / "picture.png"
    proc = _run(*words, "--png", str(png))
    assert proc.returncode == 0, proc.stderr
    assert json.loads(proc.stdout)["schema"] == schema  # the document, nothing else
    assert f"wrote {png}" in proc.stderr.splitlines()
    assert png.read_bytes().startswith(PNG)
    assert png.stat().st_size > 10_000


def test_png_of_a_grasp_in_a_new_folder(tmp_path: Path) -> None:
    """``--png``'s folder is created, like every output folder of the commands (``--rrd``, ``--out``)."""
    png = tmp_path / "new" / "solve.png"
    proc = _run("solve", "case2", "--quiet", "--png", str(png))
    assert proc.returncode == 0, proc.stderr
    assert proc.stderr == f"wrote {png}\n"
    assert png.read_bytes().startswith(PNG)


@pytest.mark.parametrize("command", ["solve", "tvms"])
@pytest.mark.parametrize(
    ("path", "message"),
    [
        ("missing/", "error: --png: expected a file name, got the folder name"),  # a folder, not yet made
        (".", "error: --png: expected a file name, got the folder"),
        ("{file}/x.png", "error: --png: expected a folder, found a file"),
    ],
)
def test_bad_png_path_is_one_line_exit_2(command: str, path: str, message: str, tmp_path: Path) -> None:
    file = tmp_path / "a-file"
    file.write_text("x")
    proc = subprocess.run(
        [*_console_script(), command, "case2", "--png", path.replace("{file}", str(file))],
        capture_output=True,
        text=True,
        check=False,
        cwd=tmp_path,
    )
    assert proc.returncode == 2
    (line,) = proc.stderr.splitlines()
    assert line.startswith(message)
    assert "Traceback" not in proc.stderr
    assert proc.stdout == ""
    assert not (tmp_path / "missing").exists()


def test_solve_without_png_does_not_import_matplotlib() -> None:
    code = (
        "import sys, contextlib, io\n"
        "from mjtvm.cli import main\n"
        "with contextlib.redirect_stdout(io.StringIO()):\n"
        "    assert main(['solve', '--quiet']) == 0\n"
        "print(sorted(m for m in sys.modules if m.split('.')[0] == 'matplotlib'))\n"
    )
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=False)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip() == "[]"
