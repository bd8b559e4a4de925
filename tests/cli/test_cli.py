"""The command line: `mjtvm solve` output, exit codes and error messages."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from benchmarks.__main__ import main as bench_main
from mjtvm import load_state, tvmmp
from mjtvm.cli import example_path
from mjtvm.cli import main as mjtvm_main
from mjtvm.grasp.resolve.file import shipped_grasps


def main(words: list[str]) -> int:
    """``mjtvm WORDS``, or ``python -m benchmarks WORDS[1:]`` where WORDS[0] is ``bench``: the
    benchmark run shares the vocabulary, the value checks and the exit codes of ``mjtvm``."""
    return bench_main(words[1:]) if words[:1] == ["bench"] else mjtvm_main(words)


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
        ["tvms", "--grasp", "case1"],
        ["export-state", "case1"],
        ["solve", "case2", "--no-witnesses"],
    ],
    ids=["solve", "tvms", "export-state", "solve-grasp"],
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
    from mjtvm.paper_hand.scenario import load_scenario

    assert main(["export-state", "case2", "--quiet"]) == 0
    path = tmp_path / "case2.json"
    path.write_text(capsys.readouterr().out)
    direct = tvmmp(load_scenario("case2").state())
    assert main(["solve", str(path), "--no-witnesses"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["alpha"] == direct.alpha.tolist()


def test_export_state_unknown_scenario_exits_2(capsys):
    assert main(["export-state", "case9"]) == 2
    assert "error: case9: no such grasp file, and not a shipped grasp (shipped: " in capsys.readouterr().err


def test_tvms_prints_the_schema_for_a_file_and_a_scenario(tmp_path, capsys):
    """`mjtvm tvms` on the exported Case 1 file equals the scenario shortcut (dimension 4)."""
    assert main(["export-state", "case1", "--quiet"]) == 0
    path = tmp_path / "case1.json"
    path.write_text(capsys.readouterr().out)
    assert main(["tvms", str(path), "--indent", "0"]) == 0
    from_file = json.loads(capsys.readouterr().out)
    assert main(["tvms", "--grasp", "case1", "--indent", "0"]) == 0
    from_scenario = json.loads(capsys.readouterr().out)
    assert main(["tvms", str(shipped_grasps()["case1"]), "--indent", "0"]) == 0  # the grasp file as STATE
    assert json.loads(capsys.readouterr().out)["vertices"] == from_scenario["vertices"]
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
    assert capsys.readouterr().err.startswith("error: --mu: expected comma-separated numbers in [0, 100]")


def test_verify_has_its_own_options(capsys):
    assert main(["verify", "--help"]) == 0
    out = " ".join(capsys.readouterr().out.split())  # argparse wraps lines at the terminal width
    assert "--armature-scale X" in out and "(number in (0, 1000]; default: 1.0)" in out


# ------------------------------------------------------- malformed calls (issue 12)
@pytest.mark.parametrize(
    ("words", "line"),
    [
        (["sweep", "--states", "1.5"], "error: --states: expected an integer in [2, 10000], got '1.5'"),
        (["sweep", "--states", "nan"], "error: --states: expected an integer in [2, 10000], got 'nan'"),
        (["sweep", "--states", "0"], "error: --states: expected an integer in [2, 10000], got '0'"),
        (["sweep", "--states", "-5"], "error: --states: expected an integer in [2, 10000], got '-5'"),
        (
            ["sweep", "--states", "0,3"],
            "error: --states: expected an integer in [2, 10000], got '0,3' (state indices",
        ),
        (["sweep", "--mu", "inf"], "error: --mu: expected comma-separated numbers in [0, 100], got 'inf'"),
        (["sweep", "--mg", "1,nan"], "error: --mg: expected comma-separated numbers in [0, 1000000]"),
        (
            ["sweep", "--state-indices", "1.5"],
            "error: --state-indices: expected comma-separated integers in [0, 9999]",
        ),
        (["sweep", "--state-indices", "30"], "error: --state-indices: expected indices below --states = 30"),
        (["sweep", "--jobs", "0"], "error: --jobs: expected an integer in [1, 64], got '0'"),
        (["sweep", "--cluster", "not an address"], "error: --cluster: expected a scheduler address"),
        (["sweep", "--cluster", "tcp://host:99999"], "error: --cluster: expected a scheduler address"),
        (["sweep", "--contacts", "X"], "error: --contacts: expected distinct values among L,S"),
        (["sweep", "--out", "results/sweep.json"], "error: --out: expected a folder"),
        (["tvms", "--time-limit", "-1"], "error: --time-limit: expected a number in (0, 86400], got '-1'"),
        (["tvms", "--time-limit", "0"], "error: --time-limit: expected a number in (0, 86400], got '0'"),
        (
            ["tvms", "--method", "cdd", "--time-limit", "nan"],
            "error: --time-limit: expected a number in (0, 86400]",
        ),
        (["solve", "--indent", "-1"], "error: --indent: expected an integer in [0, 16], got '-1'"),
        (["solve", "--solver", "gurobi"], "error: --solver: invalid choice: 'gurobi'"),
        (
            ["replay", "--tvms-every", "-1"],
            "error: --tvms-every: expected an integer in [0, 10000], got '-1'",
        ),
        (
            ["replay", "--reading", ""],
            "error: --reading: expected distinct values among physical,literal or both",
        ),
        (["verify", "--name", "a/b/c"], "error: --name: expected a file stem"),
        (["verify", "--contacts", ""], "error: --contacts: expected distinct values among L,S, got ''"),
        (["verify", "--stride", "0"], "error: --stride: expected an integer in [1, 10000], got '0'"),
        (["verify", "--window", "nan"], "error: --window: expected a number in (0, 1], got 'nan'"),
        (["bench", "--repeats", "0"], "error: --repeats: expected an integer in [1, 100000], got '0'"),
        (["bench", "--time-limit", "inf"], "error: --time-limit: expected a number in (0, 86400], got 'inf'"),
        (["frobnicate"], "error: COMMAND: invalid choice: 'frobnicate'"),
        (["sweep", "--bogus"], "error: unrecognized arguments: --bogus"),
        (["bench", "--md", "x.md"], "error: --md: no longer an option: the table is NAME.md"),
    ],
)
def test_malformed_options_exit_2_with_one_line(words, line, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)  # nothing may be written, but if it were, not into the repository
    assert main(words) == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    lines = captured.err.splitlines()
    assert len(lines) == 1 and lines[0].startswith(line), captured.err
    assert "Traceback" not in captured.err
    assert not (tmp_path / "results").exists()


# ------------------------------------------- every number and path bounded (docs/cli.md, "Bounds")
LONG = "a" * 300  # one path component over NAME_MAX (255 bytes)
MUS = ",".join(["0.5"] * 1000)


@pytest.mark.parametrize(
    ("words", "line"),
    [
        (["solve", "--indent", "99999999999999999999"],
         "error: --indent: expected an integer in [0, 16], got '99999999999999999999' (try 'mjtvm solve --help')"),
        (["solve", "--indent", "100000000"], "error: --indent: expected an integer in [0, 16], got '100000000'"),
        (["tvms", "--indent", "17"], "error: --indent: expected an integer in [0, 16], got '17'"),
        (["replay", "--states", "99999999999999999999"],
         "error: --states: expected an integer in [2, 10000], got '99999999999999999999'"),
        (["verify", "--states", "10001"], "error: --states: expected an integer in [1, 10000], got '10001'"),
        (["verify", "--stride", "10001"], "error: --stride: expected an integer in [1, 10000], got '10001'"),
        (["replay", "--tvms-every", "1e308"], "error: --tvms-every: expected an integer in [0, 10000], got '1e308'"),
        (["sweep", "--state-indices", "0,10000"],
         "error: --state-indices: expected comma-separated integers in [0, 9999], got '0,10000'"),
        (["sweep", "--jobs", "65"], "error: --jobs: expected an integer in [1, 64], got '65'"),
        (["verify", "--jobs", "99999999999999999999"], "error: --jobs: expected an integer in [1, 64]"),
        (["bench", "--repeats", "100001"], "error: --repeats: expected an integer in [1, 100000], got '100001'"),
        (["bench", "--baseline-repeats", "-1"], "error: --baseline-repeats: expected an integer in [1, 1000]"),
        (["bench", "--time-limit", "86401"], "error: --time-limit: expected a number in (0, 86400], got '86401'"),
        (["tvms", "--time-limit", "1e308"], "error: --time-limit: expected a number in (0, 86400], got '1e308'"),
        (["tvms", "--tolerance", "nan"], "error: --tolerance: expected a number in [0, 1), got 'nan'"),
        (["tvms", "--confidence", "inf"], "error: --confidence: expected a number in [0, 1), got 'inf'"),
        (["tvms", "--memory", "2000T"], "error: --memory: expected a size such as 512M, 2G or 25% (of the available "
         "memory), at most 1024T, got '2000T'"),
        (["tvms", "--memory", "1e-30%"], "error: --memory: expected a size such as 512M, 2G or 25% (of the "
         "available memory), at most 1024T, got '1e-30%'"),
        (["export-state", "case1", "--mu", "1e308"], "error: --mu: expected a number in [0, 100], got '1e308'"),
        (["export-state", "case1", "--mg=-inf"], "error: --mg: expected a number in [0, 1000000], got '-inf'"),
        (["replay", "--stop-margin", "1e308"], "error: --stop-margin: expected a number in [0, 1), got '1e308'"),
        (["verify", "--mg", "0"], "error: --mg: expected a number in (0, 1000000], got '0'"),
        (["verify", "--preload", "1e7"], "error: --preload: expected a number in [0, 1000000], got '1e7'"),
        (["verify", "--gears", "20,1e308"], "error: --gears: expected comma-separated numbers in [1, 10000], got '20,1e308'"),
        (["verify", "--gears", "1e-300"], "error: --gears: expected comma-separated numbers in [1, 10000], got '1e-300'"),
        (["verify", "--armature-scale", "1e308"], "error: --armature-scale: expected a number in (0, 1000], got '1e308'"),
        (["verify", "--window", "1e308"], "error: --window: expected a number in (0, 1], got '1e308'"),
        (["verify", "--startup", "2"], "error: --startup: expected a number in [0, 1], got '2'"),
        (["sweep", "--mu", MUS + ",0.5"], "error: --mu: expected at most 1000 comma-separated numbers, got 1001"),
        (["sweep", "--name", "n" * 201], "error: --name: expected a file stem of 1 to 200 letters"),
        (["replay", "--out", LONG], "error: --out: expected a folder whose every component has at most 255 bytes, "
         "got one of 300 bytes: 'aaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaa'... (try 'mjtvm replay --help')"),
        (["sweep", "--out", f"x/{LONG}/y"], "error: --out: expected a folder whose every component has at most 255"),
        (["replay", "--rrd", f"{LONG}.rrd"], "error: --rrd: expected a file name whose every component has at most 255"),
        (["solve", LONG], "error: STATE|GRASP: expected a file or a shipped grasp's name whose every component has "
         "at most 255 bytes, got one of 300 bytes"),
        (["export-state", f"/tmp/{LONG}.toml"], "error: GRASP: expected a file or a shipped grasp's name whose every"),
        (["tvms", "--grasp", LONG], "error: --grasp: expected a file or a shipped grasp's name whose every"),
        (["sweep", "--grasp", f"case2,{LONG}"], "error: --grasp: expected a file or a shipped grasp's name whose"),
        (["verify", "--grasp", "/" * 5000], "error: --grasp: expected a file or a shipped grasp's name of at most 4095 bytes"),
        (["bench", "--notes", "missing.txt"], "error: --notes: expected an existing file, got 'missing.txt'"),
        (["solve", "--bo\nx"], "error: unrecognized arguments: --bo\\nx (try 'mjtvm solve --help')"),
    ],
)  # fmt: skip  # a table: one command line and its error per row
def test_out_of_range_numbers_and_unusable_paths_exit_2(words, line, tmp_path, monkeypatch, capsys):
    """Each is refused while parsing: one line naming the option and the accepted range."""
    monkeypatch.chdir(tmp_path)
    assert main(words) == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    lines = captured.err.splitlines()
    assert len(lines) == 1 and lines[0].startswith(line), captured.err
    assert list(tmp_path.iterdir()) == []  # nothing created, not even --out


@pytest.mark.parametrize(
    ("words", "line"),
    [
        (["verify", "--rrd", "folder"], "error: --rrd: expected a file name, got the folder 'folder' (try 'mjtvm verify --help')"),
        (["replay", "--rrd", "folder/"], "error: --rrd: expected a file name, got the folder 'folder/'"),
        (["bench", "--notes", "folder"], "error: --notes: expected a file, got the folder 'folder' (try 'python -m benchmarks --help')"),
        (["bench", "--quick", "--out", "out", "--notes", "/dev/zero"],
         "error: --notes: expected a text file of at most 1048576 bytes, got a larger one"),
        (["bench", "--quick", "--out", "out", "--notes", "big.txt"],
         "error: --notes: expected a text file of at most 1048576 bytes, got a larger one"),
        (["bench", "--quick", "--out", "out", "--notes", "latin.txt"],
         "error: --notes: expected UTF-8 text, got byte 0xe9 at offset 3"),
    ],
)  # fmt: skip  # a table: one command line and its error per row
def test_a_folder_for_a_file_and_unbounded_notes_exit_2(words, line, tmp_path, monkeypatch, capsys):
    import benchmarks.suite

    def no_work(*args, **kwargs):  # pragma: no cover - reached only if the check came too late
        raise AssertionError("the suite started before --notes was read")

    monkeypatch.setattr(benchmarks.suite, "run_suite", no_work)
    monkeypatch.chdir(tmp_path)
    (tmp_path / "folder").mkdir()
    (tmp_path / "big.txt").write_bytes(b"x" * (2**20 + 1))
    (tmp_path / "latin.txt").write_bytes(b"caf\xe9\n")
    assert main(words) == 2
    captured = capsys.readouterr()
    lines = captured.err.splitlines()
    assert len(lines) == 1 and lines[0].startswith(line), captured.err


def test_notes_are_read_into_the_table(tmp_path, monkeypatch, capsys):
    from benchmarks import report as bench_report
    from benchmarks import suite as bench_suite

    monkeypatch.setattr(bench_suite, "run_suite", lambda **kwargs: {"schema": "benchmarks-suite/1"})
    monkeypatch.setattr(bench_report, "auto_notes", lambda report: [])
    monkeypatch.setattr(bench_report, "format_suite_table", lambda report, notes: "\n".join(notes))
    notes = tmp_path / "notes.txt"
    notes.write_text("one\ntwo\n", encoding="utf-8")
    assert main(["bench", "--quick", "--quiet", "--out", str(tmp_path), "--notes", str(notes)]) == 0
    assert json.loads((tmp_path / "bench.json").read_text())["notes"] == ["one", "two"]


def test_a_grid_too_large_is_refused_before_any_work(tmp_path, monkeypatch, capsys):
    """1000 x 10 x 30 points: refused before a lift is computed or a point is built."""
    import mjtvm.jobs.sweep_files

    def no_work(*args, **kwargs):  # pragma: no cover - reached only if the check came too late
        raise AssertionError("work started before the grid was checked")

    monkeypatch.setattr(mjtvm.jobs.sweep_files, "run_sweep_files", no_work)
    mgs = ",".join(["1"] * 10)
    assert main(["sweep", "--mu", MUS, "--mg", mgs, "--out", str(tmp_path / "o")]) == 2
    assert capsys.readouterr().err == (
        "error: --grasp x --hand x --contacts x --reading x --mu x --mg x --states: expected a grid of at "
        "most 100000 points, got 300000 (try 'mjtvm sweep --help')\n"
    )
    assert not (tmp_path / "o").exists()


def test_stdin_is_read_up_to_a_bound():
    """``mjtvm solve - < /dev/zero`` reads one byte more than a state may have, then stops."""
    with open("/dev/zero", "rb") as zero:
        proc = subprocess.run(
            [*_console_script(), "solve", "-"],
            stdin=zero,
            capture_output=True,
            text=True,
            check=False,
            timeout=120,
        )
    assert proc.returncode == 2
    assert proc.stderr == "error: -: expected a state of at most 67108864 bytes on standard input, got more\n"


def test_version_and_help_show_defaults(capsys):
    assert main(["--version"]) == 0
    assert (
        capsys.readouterr().out.strip()
        == f"mjtvm {__import__('importlib.metadata').metadata.version('mjtvm')}"
    )
    assert main(["sweep", "--help"]) == 0
    out = capsys.readouterr().out
    out = " ".join(out.split())  # argparse wraps lines at the terminal width
    assert "(integer in [2, 10000]; default: 30)" in out and "(default: results)" in out
    assert "--state-indices" in out and "default: the grasp's (0.3 for case2))" in out  # no backticks


@pytest.mark.parametrize(
    ("words", "old"),
    [
        (["export-state", "--scenario", "case2"], "--scenario"),
        (["export-state", "--variant", "humanlike"], "--variant"),
        (["sweep", "--num-states", "3"], "--num-states"),
        (["sweep", "--variants", "L"], "--variants"),
        (["replay", "--variants", "L"], "--variants"),
        (["sweep", "--readings", "physical"], "--readings"),
        (["verify", "--runs", "L,S"], "--runs"),
    ],
)
def test_one_vocabulary_the_old_spellings_are_not_options(words, old, capsys):
    """Nothing was released with them: no alias, no notice, argparse's one-line error."""
    assert main(words) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"error: unrecognized arguments: {old}") and err.count("\n") == 1


@pytest.mark.parametrize("command", [["sweep"], ["replay"], ["verify"], ["bench", "--quick"]])
def test_out_that_is_a_file_is_refused_before_any_work(command, tmp_path, capsys, monkeypatch):
    import mjtvm.jobs.replay  # imported before the patches below: they must not bind the stubs
    import mjtvm.jobs.sweep_files
    import mjtvm.jobs.verify

    def no_work(*args, **kwargs):  # pragma: no cover - reached only if the check came too late
        raise AssertionError("work started before --out was checked")

    monkeypatch.setattr(mjtvm.jobs.sweep_files, "run_sweep", no_work)
    monkeypatch.setattr("benchmarks.suite.run_suite", no_work)
    monkeypatch.setattr("mjtvm.lift.trajectory.scripted_lift", no_work)
    monkeypatch.setattr("mjtvm.jobs.replay.scripted_lift", no_work)
    monkeypatch.setattr("mjtvm.jobs.verify.verify_lift", no_work)
    blocker = tmp_path / "file"
    blocker.write_text("x")
    for out, problem in (
        (blocker, "expected a folder, found a file"),
        (blocker / "sub", "cannot create the folder"),
    ):
        assert main([*command, "--out", str(out), "--quiet"]) == 2
        assert capsys.readouterr().err.startswith(f"error: --out: {problem}")
    assert main([*command, "--out", "/proc/mjtvm-cannot-be-here", "--quiet"]) == 2
    assert capsys.readouterr().err.startswith("error: --out: cannot create the folder")


def test_a_second_run_into_a_locked_folder_is_refused(tmp_path, capsys):
    """Two runs into one folder (two replays with different --mu) must not interleave rows."""
    from mjtvm.formats.files import output_lock

    with output_lock(tmp_path):
        assert main(["replay", "--out", str(tmp_path), "--states", "2", "--no-sweeps", "--quiet"]) == 2
        err = capsys.readouterr().err
        assert (
            err
            == f"error: --out: another mjtvm run is writing to this folder (its lock is held): {tmp_path}\n"
        )
    assert not (tmp_path / "lift.csv").exists()


def test_write_failure_leaves_the_old_files_and_no_temporaries(tmp_path, monkeypatch):
    """/dev/full-like failure at write time: an OutputError naming the file; the old set stays."""
    import errno
    import os

    from mjtvm.errors import OutputError
    from mjtvm.formats.files import write_files

    old = {tmp_path / "lift.csv": "old csv", tmp_path / "lift.json": "old json"}
    write_files(old)
    calls = []

    def full(fd):
        calls.append(fd)
        if len(calls) == 2:  # the second file of the set
            raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(os, "fsync", full)
    with pytest.raises(OutputError, match=r"--out: cannot write \(No space left on device\): .*lift.json"):
        write_files({tmp_path / "lift.csv": "new csv", tmp_path / "lift.json": "new json"})
    assert {p.name: p.read_text() for p in tmp_path.iterdir()} == {
        "lift.csv": "old csv",
        "lift.json": "old json",
    }


def test_unreachable_cluster_is_one_line_after_the_timeout(tmp_path, monkeypatch, capsys):
    import socket

    import mjtvm.jobs.sweep

    monkeypatch.setattr(mjtvm.jobs.sweep, "CONNECT_TIMEOUT_S", 1.0)
    with socket.socket() as s:  # a port that nobody listens on
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    words = [
        "sweep",
        "--cluster",
        f"tcp://127.0.0.1:{port}",
        "--states",
        "2",
        "--out",
        str(tmp_path),
        "--quiet",
    ]
    assert main(words) == 2
    err = capsys.readouterr().err
    assert err.startswith(
        f"error: --cluster: cannot reach a Dask scheduler at tcp://127.0.0.1:{port} within 1 s"
    )
    assert len(err.splitlines()) == 1
    assert not (tmp_path / "sweep.json").exists()


# ------------------------------------------------- the installed script (subprocesses)
def test_closed_stdout_is_quiet():
    """`mjtvm solve | head -c 10` with head gone before the write: no BrokenPipeError trace."""
    proc = subprocess.Popen([*_console_script(), "solve"], stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    assert proc.stdout is not None and proc.stderr is not None
    proc.stdout.close()
    err = proc.stderr.read().decode()
    assert proc.wait(timeout=60) == 141
    assert err == ""


def test_full_stdout_is_one_line():
    with open("/dev/full", "w") as full:
        proc = subprocess.run(
            [*_console_script(), "solve"],
            stdout=full,
            capture_output=False,
            stderr=subprocess.PIPE,
            text=True,
            check=False,
        )
    assert proc.returncode == 2
    assert proc.stderr == "error: standard output: cannot write (No space left on device): <stdout>\n"


def test_ctrl_c_during_a_sweep_is_one_line_and_leaves_no_partial_file(tmp_path):
    """SIGINT once the sweep's progress bar has moved (event-driven: inside the LPs, whatever the
    machine's load), on a grid long enough (144 x 30 points) not to finish first."""
    import re
    import signal
    import threading

    mus = ",".join(f"{0.02 * k:.2f}" for k in range(1, 25))
    words = ["sweep", "--mu", mus, "--mg", "0.5,1,1.5,2,2.5,3", "--out", str(tmp_path)]
    proc = subprocess.Popen(
        [*_console_script(), *words], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
    )
    err_parts: list[str] = []
    moving = threading.Event()

    def read_stderr() -> None:
        assert proc.stderr is not None
        while chunk := proc.stderr.read(1):
            err_parts.append(chunk)
            if re.search(r"\|\s*[1-9][0-9]*/[0-9]+ ", "".join(err_parts[-80:])):  # a row is finished
                moving.set()

    reader = threading.Thread(target=read_stderr, daemon=True)
    reader.start()
    assert moving.wait(timeout=120), "".join(err_parts)
    proc.send_signal(signal.SIGINT)
    proc.wait(timeout=60)
    reader.join(timeout=10)
    err = "".join(err_parts)
    assert proc.returncode == 130, err
    assert err.rstrip("\n").splitlines()[-1].endswith("mjtvm: interrupted") and "Traceback" not in err
    names = {p.name for p in tmp_path.iterdir()}
    assert names <= {".mjtvm.lock", "sweep.partial.json"}  # no result, no temporary file
    if "sweep.partial.json" in names:  # complete JSON: the finished rows
        doc = json.loads((tmp_path / "sweep.partial.json").read_text())
        assert doc["schema"] == "mjtvm.sweep-checkpoint/1"


def test_progress_of_tvms_and_bench_goes_to_stderr(tmp_path, monkeypatch, capsys):
    assert main(["tvms", "--grasp", "case1", "--indent", "0"]) == 0
    captured = capsys.readouterr()
    assert json.loads(captured.out)["schema"] == "mjtvm.tvms/1" and " LP" in captured.err
    assert main(["tvms", "--grasp", "case1", "--quiet"]) == 0
    assert capsys.readouterr().err == ""

    from benchmarks import report as bench_report
    from benchmarks import suite as bench_suite

    def suite(**kwargs):
        for step in ("case 1, problem 1", "case 1, problem 2", "scaling"):
            kwargs["progress"](step)
        return {"schema": "benchmarks-suite/1"}

    monkeypatch.setattr(bench_suite, "run_suite", suite)
    monkeypatch.setattr(bench_report, "auto_notes", lambda report: [])
    monkeypatch.setattr(bench_report, "format_suite_table", lambda report, notes: "TABLE")
    assert main(["bench", "--quick", "--out", str(tmp_path), "--name", "b"]) == 0
    captured = capsys.readouterr()
    assert "bench: scaling" in captured.err and captured.out.startswith("TABLE\n")
    assert json.loads((tmp_path / "b.json").read_text())["schema"] == "benchmarks-suite/1"
    assert (tmp_path / "b.md").read_text() == "```\nTABLE\n```\n"


def test_solve_warns_on_stderr_of_a_pair_that_is_not_certified(monkeypatch, capsys):
    """A pair whose answer no way certified: the JSON says so (certified false, its note) and
    stderr has one line naming the pair; the exit code stays 0."""
    from dataclasses import replace

    import mjtvm.cli.solve as cli_solve

    real = cli_solve.tvmmp

    def doubtful(*args, **kwargs):  # type: ignore[no-untyped-def]
        r = real(*args, **kwargs)
        certified = tuple(
            tuple(False if (k, l) == (0, 1) else c for l, c in enumerate(row))
            for k, row in enumerate(r.certified)
        )
        return replace(r, certified=certified, notes=(((0, 1), "not certified: highs: gap 1e-3"),))

    monkeypatch.setattr(cli_solve, "tvmmp", doubtful)
    assert main(["solve", "--no-witnesses"]) == 0
    out, err = capsys.readouterr()
    doc = json.loads(out)
    assert doc["certified"][0][1] is False and doc["notes"][0]["pair"] == [0, 1]
    assert err == "mjtvm: warning: alpha[0][1] is not certified: not certified: highs: gap 1e-3\n"


@pytest.mark.parametrize("unbuffered", ["", "1"])
def test_stdout_closed_after_the_first_byte_exits_141(unbuffered):
    """`mjtvm tvms allegro-ik | head -c 1`: 140 kB of JSON, the reader gone after one byte.
    Unbuffered (PYTHONUNBUFFERED=1), the text layer used to drop the rest of a partial write
    silently and exit 0; now every command exits 141, without a traceback."""
    import os

    env = {k: v for k, v in os.environ.items() if k != "PYTHONUNBUFFERED"}
    if unbuffered:
        env["PYTHONUNBUFFERED"] = unbuffered
    proc = subprocess.Popen(
        [*_console_script(), "tvms", "allegro-ik", "--quiet"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        env=env,
    )
    assert proc.stdout is not None and proc.stderr is not None
    assert len(proc.stdout.read(1)) == 1  # the output has started: more than the pipe holds follows
    proc.stdout.close()
    err = proc.stderr.read().decode()
    assert proc.wait(timeout=120) == 141
    assert err == ""


@pytest.mark.parametrize(
    ("words", "message"),
    [
        (
            ["show", "case2", "--grasp", "case1"],
            "error: --grasp: give GRASP or --grasp, not both (try 'mjtvm show --help')\n",
        ),
        (
            ["export-state", "case2", "--grasp", "case1"],
            "error: --grasp: give GRASP or --grasp, not both (try 'mjtvm export-state --help')\n",
        ),
        (
            ["verify", "--launch", "0.01", "--gears", "10,20"],
            "error: --gears: replaces the rollouts, which --launch is an option of: give one of them, not both "
            "(try 'mjtvm verify --help')\n",
        ),
        (
            ["verify", "--gears", "10", "--dynamics"],
            "error: --gears: replaces the rollouts, which --dynamics is an option of: give one of them, not both "
            "(try 'mjtvm verify --help')\n",
        ),
        (
            ["verify", "--gears", "10", "--hold-drive", "squeeze"],
            "error: --gears: replaces the rollouts, which --hold-drive is an option of: give one of them, "
            "not both (try 'mjtvm verify --help')\n",
        ),
        (["--version", "x"], "error: --version: takes no other arguments, got 'x' (try 'mjtvm --help')\n"),
    ],
)
def test_contradictory_invocations_are_one_line_and_exit_2(words, message, capsys, tmp_path):
    """Two answers to one question (which grasp; rollouts or the gear sweep; the version or a
    command): refused before any work, in one line, never one of them silently dropped."""
    if words[0] == "verify":
        words = [*words, "--out", str(tmp_path)]
    assert main(words) == 2
    captured = capsys.readouterr()
    assert captured.err == message
    assert captured.out == ""
    assert not any(tmp_path.iterdir())  # nothing written
