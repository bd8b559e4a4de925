"""The command line: `mjtvm solve` output, exit codes and error messages."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from mjtvm import load_state, tvmmp
from mjtvm.cli import example_path, main


def test_solve_prints_the_result_schema(capsys):
    assert main(["solve", example_path(), "--no-witnesses"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["schema"] == "mjtvm.result/1"
    assert set(out) >= {"tvmmp", "feasible", "alpha", "status", "distribution"}
    assert "witnesses" not in out
    assert out["tvmmp"] == tvmmp(load_state(example_path())).tvmmp


def test_solve_defaults_to_the_shipped_example_and_reads_stdin(capsys, monkeypatch):
    assert main(["solve"]) == 0
    default = json.loads(capsys.readouterr().out)
    assert default["witnesses"][0][0]["torques"]
    with open(example_path()) as f:
        monkeypatch.setattr(sys, "stdin", f)
        assert main(["solve", "-", "--solver", "clarabel", "--box", "literal"]) == 0
    other = json.loads(capsys.readouterr().out)
    assert other["tvmmp"] == pytest.approx(default["tvmmp"], rel=1e-7)


def test_bad_state_exits_2_naming_the_field(tmp_path, capsys):
    doc = json.loads(open(example_path()).read())
    doc["contacts"][1]["normal"] = [0.0, 0.0, 2.0]
    path = tmp_path / "bad.json"
    path.write_text(json.dumps(doc))
    assert main(["solve", str(path)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: contacts[1].normal: expected a unit vector")


def _console_script() -> list[str]:
    """The installed ``mjtvm`` script beside this interpreter (as a user runs it), else ``-m``."""
    script = Path(sys.executable).with_name("mjtvm")
    return [str(script)] if script.exists() else [sys.executable, "-m", "mjtvm.cli"]


@pytest.mark.parametrize(
    "words",
    [
        ["solve", "--no-witnesses", "--indent", "0"],
        ["tvms", "--scenario", "case1"],
        ["export-state", "--scenario", "case1"],
    ],
    ids=["solve", "tvms", "export-state"],
)
def test_console_script_stdout_is_pure_json(words):
    """What C++ libraries write to file descriptor 1 (highspy >= 1.16 prints a banner when its
    first solver is created) is invisible to in-process tests: run the script as a user pipes it."""
    proc = subprocess.run([*_console_script(), *words], capture_output=True, text=True, check=False)
    assert proc.returncode == 0, proc.stderr
    assert "Traceback" not in proc.stderr
    doc = json.loads(proc.stdout)
    assert doc["schema"].startswith("mjtvm.")


def test_export_state_round_trips_through_solve(tmp_path, capsys):
    """The exported JSON is an ordinary mjtvm.state/1 file: solving it gives exactly the
    alphas of the state built in memory from MuJoCo."""
    from mjtvm.scenario import load_scenario

    assert main(["export-state", "--scenario", "case2"]) == 0
    path = tmp_path / "case2.json"
    path.write_text(capsys.readouterr().out)
    direct = tvmmp(load_scenario("case2").state())
    assert main(["solve", str(path), "--no-witnesses"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["alpha"] == direct.alpha.tolist()


def test_export_state_unknown_scenario_exits_2(capsys):
    assert main(["export-state", "--scenario", "case9"]) == 2
    assert "case9" in capsys.readouterr().err


def test_tvms_prints_the_schema_for_a_file_and_a_scenario(tmp_path, capsys):
    """`mjtvm tvms` on the exported Case 1 file equals the scenario shortcut (dimension 4)."""
    assert main(["export-state", "--scenario", "case1"]) == 0
    path = tmp_path / "case1.json"
    path.write_text(capsys.readouterr().out)
    assert main(["tvms", str(path), "--indent", "0"]) == 0
    from_file = json.loads(capsys.readouterr().out)
    assert main(["tvms", "--scenario", "case1", "--indent", "0"]) == 0
    from_scenario = json.loads(capsys.readouterr().out)
    assert from_file["schema"] == "mjtvm.tvms/1" and from_file["dimension"] == 4
    assert from_file["vertices"] == from_scenario["vertices"]
    assert main(["tvms"]) == 2
    assert "give a mjtvm.state/1 file" in capsys.readouterr().err


def test_sweep_writes_rows_and_rejects_bad_numbers(tmp_path, capsys):
    args = [
        "sweep",
        "--mu",
        "0.1,0.5",
        "--state-indices",
        "0",
        "--states",
        "4",
        "--out",
        str(tmp_path),
        "--quiet",
    ]
    assert main(args) == 0
    rows = json.loads((tmp_path / "sweep.json").read_text())
    assert [r["mu"] for r in rows] == [0.1, 0.5] and all(r["feasible"] for r in rows)
    assert (tmp_path / "sweep.csv").read_text().count("\n") == 3
    assert not (tmp_path / "sweep.partial.json").exists()
    assert main(["sweep", "--mu", "lots", "--out", str(tmp_path)]) == 2
    assert capsys.readouterr().err.startswith("error: --mu: expected comma-separated finite numbers >= 0")


def test_verify_has_its_own_options(capsys):
    assert main(["verify", "--help"]) == 0
    out = capsys.readouterr().out
    assert "--armature-scale" in out and "(default: 1.0)" in out
