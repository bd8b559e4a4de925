"""``docs/outputs.md`` against what the commands write.

Each field table of the page follows a marker ``<!-- fields: NAME -->``; its first column
holds the documented columns or keys as code spans (``alpha_k<k>_l<l>`` stands for one
column per pair). The tests run the real writers on small inputs (a lift of 2-3 states, a
sweep of 2 points, one or two states of the physics check, the benchmark's sections on the
smallest inputs) and check that the documented set equals the written set.
"""

from __future__ import annotations

import csv
import io
import json
import re
from collections.abc import Iterable
from pathlib import Path
from typing import Any

import pytest

from mjtvm.jobs.sweep_files import SweepFiles

DOC = Path(__file__).resolve().parents[2] / "docs" / "outputs.md"
_MARKER = re.compile(r"<!--\s*fields:\s*(\S+)\s*-->")
_CELL = re.compile(r"^\|\s*`([^`]+)`")


def field_tables(text: str) -> dict[str, list[str]]:
    """``{marker name: [documented field, ...]}``: the first-column code spans of the table
    that follows each marker."""
    tables: dict[str, list[str]] = {}
    lines = text.splitlines()
    for i, line in enumerate(lines):
        m = _MARKER.search(line)
        if not m:
            continue
        names: list[str] = []
        j = i + 1
        while j < len(lines) and not lines[j].startswith("|"):
            j += 1
        j += 2  # the header and its separator
        while j < len(lines) and lines[j].startswith("|"):
            cell = _CELL.match(lines[j])
            assert cell, f"{m.group(1)}: a row without a field name in backticks: {lines[j]!r}"
            names.append(cell.group(1))
            j += 1
        assert names, f"the table of {m.group(1)} is empty"
        assert m.group(1) not in tables, f"two tables named {m.group(1)}"
        tables[m.group(1)] = names
    return tables


TABLES = field_tables(DOC.read_text(encoding="utf-8"))


def _pattern(name: str) -> re.Pattern[str]:
    """A documented name as a regex: ``<k>``, ``<l>`` (any placeholder) stand for an index."""
    parts = re.split(r"<[a-z]+>", name)
    return re.compile(r"\d+".join(re.escape(p) for p in parts) + r"\Z")


def assert_documented(table: str, written: Iterable[str]) -> None:
    """Every written field matches a documented one and every documented one is written."""
    documented = TABLES[table]
    written = list(dict.fromkeys(written))
    patterns = {name: _pattern(name) for name in documented}
    undocumented = [w for w in written if not any(p.match(w) for p in patterns.values())]
    unwritten = [n for n, p in patterns.items() if not any(p.match(w) for w in written)]
    assert not undocumented, f"{table}: written but not in docs/outputs.md: {undocumented}"
    assert not unwritten, f"{table}: in docs/outputs.md but not written: {unwritten}"


def _header(path: Path) -> list[str]:
    with path.open(newline="", encoding="utf-8") as f:
        return next(csv.reader(f))


def _csv_header(text: str) -> list[str]:
    return next(csv.reader(io.StringIO(text)))


def test_every_table_is_parsed() -> None:
    expected = {
        "lift.csv",
        "lift-sweeps.csv",
        "lift.json",
        "lift.json:lift",
        "lift.json:record",
        "lift.json:sweeps",
        "lift.json:timings",
        "sweep.json:row",
        "sweep.csv",
        "sweep.partial.json",
        "rank.json:row",
        "rank.json:sim",
        "rank-auc.csv",
        "rank.csv",
        "rank-objects.csv",
        "rank.partial.jsonl",
        "verify.csv",
        "slide-check.csv",
        "gears.csv",
        "bench.json",
        "bench.json:machine",
        "bench.json:settings",
        "bench.json:stats",
        "bench.json:problem1",
        "bench.json:problem2",
        "bench.json:lift",
        "bench.json:sweeps",
        "bench.json:scaling",
        "bench.json:scaling.per_fingers",
        "bench.json:hands",
        "bench.json:dataset",
        "bench.json:dataset.batch",
        "bench.json:dataset.cli",
        "bench.json:peers",
        "bench.json:peers.finger",
        "bench.json:peers.pair",
        "bench.json:peers.agreement",
        "bench.json:floor",
        "bench.json:floor.state",
        "bench.json:floor.compiled",
        "bench.json:rank",
        "show",  # tested in tests/cli/test_show.py
        "show-contacts",
    }
    assert set(TABLES) == expected


# ------------------------------------------------------------------ mjtvm replay
@pytest.fixture(scope="module")
def replay_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    from mjtvm.jobs.replay import run_replay

    out = tmp_path_factory.mktemp("replay")
    run_replay(num_states=3, plots=False, sweeps=True, out=out)
    return out


def test_lift_csv(replay_dir: Path) -> None:
    assert_documented("lift.csv", _header(replay_dir / "lift.csv"))


def test_lift_sweeps_csv(replay_dir: Path) -> None:
    header = _header(replay_dir / "lift-sweeps.csv")
    assert header[1:] == _header(replay_dir / "lift.csv"), "lift-sweeps.csv is `sweep` + lift.csv's columns"
    assert_documented("lift-sweeps.csv", header[:1])


def test_lift_json(replay_dir: Path) -> None:
    doc = json.loads((replay_dir / "lift.json").read_text(encoding="utf-8"))
    assert_documented("lift.json", doc)
    assert_documented("lift.json:lift", doc["lift"])
    records = doc["records"] + doc["sweeps"]["mu"]["records"] + doc["sweeps"]["mg"]["records"]
    assert records
    for record in records:
        assert_documented("lift.json:record", record)
    assert_documented("lift.json:sweeps", doc["sweeps"])
    assert set(doc["sweeps"]["mu"]) == {"mg", "values", "records"}
    assert set(doc["sweeps"]["mg"]) == {"mu", "values", "records"}
    assert_documented("lift.json:timings", doc["timings"])


# ------------------------------------------------------------------ mjtvm sweep
def _sweep_args(out: Path) -> SweepFiles:
    return SweepFiles(
        scenarios=("case2",), hands=("default",), variants=("L",), readings=("physical",),
        num_states=3, states=(0, 1), out=out, name="sweep", quiet=True,
    )  # fmt: skip  # a table: the grid, then the files


def test_sweep_files(tmp_path: Path) -> None:
    from mjtvm.jobs.sweep_files import run_sweep_files

    run_sweep_files(_sweep_args(tmp_path), emit=lambda _: None, notice=lambda _: None)
    rows = json.loads((tmp_path / "sweep.json").read_text(encoding="utf-8"))
    assert len(rows) == 2
    for row in rows:
        assert_documented("sweep.json:row", row)
    assert_documented("sweep.csv", _header(tmp_path / "sweep.csv"))
    assert not (tmp_path / "sweep.partial.json").exists()


def test_sweep_checkpoint(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """The checkpoint a failing sweep leaves behind (the rows finished before the failure)."""
    from mjtvm.jobs import sweep_files

    real = sweep_files.run_sweep

    def failing(points: Any, **kwargs: Any) -> Any:
        real(points, **kwargs)
        raise RuntimeError("stop after the rows")

    monkeypatch.setattr(sweep_files, "CHECKPOINT_EVERY_S", 1e9)
    monkeypatch.setattr(sweep_files, "run_sweep", failing)
    with pytest.raises(RuntimeError, match="stop after the rows"):
        sweep_files.run_sweep_files(_sweep_args(tmp_path), emit=lambda _: None, notice=lambda _: None)
    doc = json.loads((tmp_path / "sweep.partial.json").read_text(encoding="utf-8"))
    assert_documented("sweep.partial.json", doc)
    assert doc["rows"]
    for row in doc["rows"]:
        assert_documented("sweep.json:row", row)


# ------------------------------------------------------------------ mjtvm rank
def test_rank_files(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Rows of evaluated, infeasible and failed grasps; the Parquet file's columns; the checkpoint."""
    import numpy as np

    from mjtvm.jobs import rank, rank_files

    root = Path(__file__).resolve().parents[2]
    z = np.load(root / "mjtvm" / "data" / "examples" / "shadow-sphere-dataset.npz")
    rows = [0, 1, len(z["id"]) - 2, len(z["id"]) - 1]  # infeasible, evaluated, the two broken
    np.savez(tmp_path / "d.npz", **{k: v[rows] for k, v in z.items()})
    grasp = str(root / "models" / "shadow_hand" / "shadow_hand-sphere.toml")
    run = rank_files.RankFiles(
        grasp=grasp,
        datasets=(str(tmp_path / "d.npz"),),
        out=tmp_path,
        plots=False,
        quiet=True,
        refuse_penetration=True,
    )
    rank_files.run_rank_files(run, emit=lambda _: None, notice=lambda _: None)
    written = json.loads((tmp_path / "rank.json").read_text(encoding="utf-8"))
    assert {r["failure"] for r in written} == {None, "no contact", "penetration"}
    for row in written:
        assert_documented("rank.json:row", row)
    assert_documented("rank.csv", _header(tmp_path / "rank.csv"))
    assert_documented("rank-objects.csv", _header(tmp_path / "rank-objects.csv"))
    import pyarrow.parquet as pq

    assert pq.read_table(tmp_path / "rank.parquet").column_names == _header(tmp_path / "rank.csv")

    def failing(*args: Any, **kwargs: Any) -> Any:
        rank.stream_rows(*args, **kwargs)
        raise RuntimeError("stop after the rows")

    monkeypatch.setattr(rank_files, "stream_rows", failing)
    with pytest.raises(RuntimeError, match="stop after the rows"):
        rank_files.run_rank_files(run, emit=lambda _: None, notice=lambda _: None)
    head, *lines = (tmp_path / "rank.partial.jsonl").read_text(encoding="utf-8").splitlines()
    assert_documented("rank.partial.jsonl", json.loads(head))
    assert len(lines) == len(rows)
    for line in lines:
        assert_documented("rank.json:row", json.loads(line))


def test_rank_verify_files(tmp_path: Path) -> None:
    """``--verify``: the simulated columns after the others in every row, and the AUC table."""
    import numpy as np

    from mjtvm.jobs import rank_files

    root = Path(__file__).resolve().parents[2]
    z = np.load(root / "mjtvm" / "data" / "examples" / "shadow-sphere-dataset.npz")
    np.savez(tmp_path / "d.npz", **{k: v[[0, 1]] for k, v in z.items()})  # infeasible, evaluated
    run = rank_files.RankFiles(
        grasp=str(root / "models" / "shadow_hand" / "shadow_hand_coupled-sphere.toml"),
        datasets=(str(tmp_path / "d.npz"),),
        out=tmp_path,
        plots=False,
        quiet=True,
        verify=True,
        hold_time=0.2,
    )
    rank_files.run_rank_files(run, emit=lambda _: None, notice=lambda _: None)
    plain = set(TABLES["rank.json:row"])
    for row in json.loads((tmp_path / "rank.json").read_text(encoding="utf-8")):
        assert_documented("rank.json:row", [k for k in row if k in plain])
        assert_documented("rank.json:sim", [k for k in row if k not in plain])
    header = _header(tmp_path / "rank.csv")
    assert_documented("rank.json:sim", [k for k in header if k in TABLES["rank.json:sim"]])
    assert_documented("rank-auc.csv", _header(tmp_path / "rank-auc.csv"))
    doc = json.loads((tmp_path / "rank-auc.json").read_text(encoding="utf-8"))
    for row in doc["rows"]:
        assert_documented("rank-auc.csv", row)


# ------------------------------------------------------------------ mjtvm verify
@pytest.fixture(scope="module")
def lift2() -> Any:
    from mjtvm.jobs import verify

    return verify.cached_lift("case2", 2)


def test_verify_csv(tmp_path: Path, lift2: Any) -> None:
    from mjtvm.jobs import verify

    rows = verify.verify_lift(
        "case2",
        num_states=2,
        stride=1,
        runs=("L",),
        dynamics=True,
        launch_distance=0.002,
        out=tmp_path,
        name="verify",
        progress=False,
        plot=False,
    )
    assert rows
    assert_documented("verify.csv", _header(tmp_path / "verify.csv"))


def test_slide_check_csv(lift2: Any) -> None:
    from mjtvm.jobs import verify
    from mjtvm.jobs.slide_check import slide_check

    rows = slide_check(lift2, [0])
    assert rows
    assert_documented("slide-check.csv", _csv_header(verify.rows_csv(rows)))


def test_gears_csv(lift2: Any) -> None:
    from mjtvm.jobs import verify
    from mjtvm.jobs.gears import gear_sweep

    rows = gear_sweep("case2", [40.0], num_states=2, states=[0])
    assert_documented("gears.csv", _csv_header(verify.rows_csv(rows)))


# ------------------------------------------------------------------ python -m benchmarks
def test_bench_json(monkeypatch: pytest.MonkeyPatch) -> None:
    """The suite with each section on its smallest input (the report's structure is the same)."""
    from benchmarks import cases, dataset, hands, peers, scaling, suite
    from mjtvm.data import __file__ as data_init
    from mjtvm.formats.state_file import load_state

    pinch = load_state(Path(data_init).parent / "examples" / "pinch.json")

    def small_cases(**_: Any) -> dict[str, Any]:
        return {
            "case1_p1": cases.bench_problem1(pinch, repeats=1, warmup=0, cdd=False),
            "case1_p2": {
                **cases.bench_problem2(pinch, repeats=1, baseline_repeats=1, warmup=0),
                "beta": [0.0],
            },
        }

    real_lift, real_sweeps = suite.bench_lift, suite.bench_sweeps
    monkeypatch.setattr(suite, "paper_cases", small_cases)
    monkeypatch.setattr(suite, "bench_lift", lambda **_: real_lift(repeats=1, num_states=2))
    monkeypatch.setattr(suite, "bench_sweeps", lambda **_: real_sweeps(jobs=(1, 2), repeats=1, num_states=2))
    monkeypatch.setattr(
        suite, "bench_scaling", lambda f, **_: scaling.bench_scaling((2, 4), repeats=1, p1_repeats=1)
    )
    monkeypatch.setattr(
        suite, "bench_hands", lambda h, **_: hands.bench_hands(("gripper3-box",), repeats=1, lift_repeats=1)
    )
    real_dataset = dataset.bench_dataset
    monkeypatch.setattr(
        dataset, "bench_dataset", lambda **_: real_dataset(num_states=4, repeats=1, cli_repeats=1)
    )
    real_peers = peers.bench_peers
    monkeypatch.setattr(peers, "bench_peers", lambda **_: real_peers((3,), repeats=1, lp_repeats=1))
    from benchmarks import floor

    real_floor = floor.bench_floor
    monkeypatch.setattr(floor, "bench_floor", lambda **_: real_floor(repeats=1, warmup=0))
    from benchmarks import rank as rank_bench

    real_rank, real_jobs = rank_bench.bench_rank, rank_bench.bench_jobs
    monkeypatch.setattr(rank_bench, "bench_jobs", lambda **_: real_jobs(copies=1))
    monkeypatch.setattr(
        rank_bench,
        "bench_rank",
        lambda **kw: real_rank(
            repeats=1, sizes=kw["sizes"], grasps_22=4, verify_grasps=2, say=kw.get("say", print)
        ),
    )
    report = suite.run_suite(scale=False, progress=False, rank_sizes=(8,))
    report["notes"] = []  # added by the command (benchmarks.__main__) before writing
    report["problem1_scale"] = {}  # not run here (minutes, fresh processes); documented in prose
    assert_documented("bench.json", report)
    assert_documented("bench.json:machine", report["machine"])
    assert_documented("bench.json:settings", report["settings"])
    assert_documented("bench.json:problem1", report["cases"]["case1_p1"])
    assert_documented("bench.json:problem2", report["cases"]["case1_p2"])
    assert_documented("bench.json:lift", report["lift"])
    assert_documented("bench.json:sweeps", report["sweeps"])
    assert_documented("bench.json:scaling", report["scaling"])
    for entry in report["scaling"]["per_fingers"].values():
        assert_documented("bench.json:scaling.per_fingers", entry)
    assert_documented("bench.json:dataset", report["dataset"])
    for key in ("batch_weight", "batch_six_wrenches"):
        assert_documented("bench.json:dataset.batch", report["dataset"][key])
    assert_documented("bench.json:dataset.cli", report["dataset"]["cli"])
    assert_documented("bench.json:peers", report["peers"])
    finger = report["peers"]["fingers"]["3"]
    assert_documented("bench.json:peers.finger", finger)
    for pair in (
        finger["tvms"],
        finger["function"],
        finger["force"],
        report["peers"]["four_link_example"]["force"],
    ):
        assert_documented("bench.json:peers.pair", pair)
    assert_documented("bench.json:peers.agreement", finger["vs_lp"])
    assert_documented("bench.json:rank", report["rank"])
    assert_documented("bench.json:floor", report["floor"])
    states = report["floor"]["states"]
    assert "dataset-36-compiled" in states
    for name, entry in states.items():
        table = "bench.json:floor.compiled" if name.endswith("-compiled") else "bench.json:floor.state"
        assert_documented(table, entry)
    for entry in report["hands"].values():
        assert_documented("bench.json:hands", entry)
        assert_documented("bench.json:stats", entry["load"])
