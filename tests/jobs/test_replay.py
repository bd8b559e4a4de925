"""The replay of the lift (mjtvm.jobs.replay) and `mjtvm replay`: files, consistency, options."""

from __future__ import annotations

import csv
import json
import math
from pathlib import Path

import numpy as np
import pytest

from mjtvm.cli import main
from mjtvm.errors import ParamError
from mjtvm.jobs.replay import SWEEP_MGS, SWEEP_MUS, ReplayOutput, run_replay, time_replay
from mjtvm.jobs.replay_records import solve_state
from mjtvm.lift.states import lift_state, slide_directions

STATES = 4


@pytest.fixture(scope="module")
def output(tmp_path_factory: pytest.TempPathFactory) -> ReplayOutput:
    out = tmp_path_factory.mktemp("replay")
    return run_replay(out=out, num_states=STATES, readings=("physical", "literal"))


def _rows(path: Path) -> list[dict[str, str]]:
    with path.open(newline="", encoding="utf-8") as f:
        return list(csv.DictReader(f))


def _value(text: str) -> float | None:
    return None if text == "" else float(text)


def test_replay_writes_every_file(output: ReplayOutput) -> None:
    names = {"lift.csv", "lift.json", "lift-sweeps.csv", "fig8.png", "fig9a.png", "fig9b.png"}
    assert set(output.files) == names
    for path in output.files.values():
        assert path.stat().st_size > 0
        if path.suffix == ".png":
            assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_csv_json_and_a_fresh_solve_agree(output: ReplayOutput) -> None:
    rows = _rows(output.files["lift.csv"])
    doc = json.loads(output.files["lift.json"].read_text(encoding="utf-8"))
    # one row per (variant, reading, state): L once, S under each reading
    runs = [("L", ""), ("S", "physical"), ("S", "literal")]
    assert [(r["variant"], r["reading"], int(r["state"])) for r in rows] == [
        (v, rd, i) for v, rd in runs for i in range(STATES)
    ]
    assert len(doc["records"]) == len(rows)
    assert doc["schema"] == "mjtvm.lift/1" and doc["scenario"] == "case2" and doc["hand"] == "default"
    assert doc["mu"] == 0.3 and doc["mg"] == 1.0 and doc["readings"] == ["physical", "literal"]
    assert len(doc["lift"]["residual"]) == STATES and max(map(max, doc["lift"]["residual"])) < 1e-6
    lift = output.lift
    for row, rec in zip(rows, doc["records"], strict=True):
        assert rec["state"] == int(row["state"]) and rec["z"] == float(row["z"])
        assert rec["tvmmp"] == _value(row["tvmmp"])
        assert rec["feasible"] == (row["feasible"] == "True")
        assert row["certified"] == str(all(c is not False for c in rec["certified"][0])) == "True"
        for l, alpha in enumerate(rec["alpha"][0]):
            assert alpha == _value(row[f"alpha_k0_l{l}"])
            assert rec["status"][0][l] == row[f"status_k0_l{l}"]
        reading = row["reading"] or "physical"
        state = lift_state(lift, int(row["state"]), variant=row["variant"], reading=reading, mu=0.3, mg=1.0)
        fresh, _ = solve_state(state)
        if fresh.tvmmp is None:
            assert rec["tvmmp"] is None
        else:
            assert rec["tvmmp"] == pytest.approx(fresh.tvmmp, rel=1e-9)
        if rec["limiting"] is not None:
            assert [int(row["limiting_k"]), int(row["limiting_l"])] == rec["limiting"]
            assert rec["tvmmp"] == min(a for a in rec["alpha"][0] if a is not None)


def test_slide_directions_in_the_json_are_opposite(output: ReplayOutput) -> None:
    slides = json.loads(output.files["lift.json"].read_text(encoding="utf-8"))["lift"]["slide_directions"]
    for i, (phys, lit) in enumerate(zip(slides["physical"], slides["literal"], strict=True)):
        assert set(phys) == {"f2_tip", "f4_tip"}
        for geom in phys:
            assert np.allclose(lit[geom], -np.array(phys[geom]), atol=0.0)
            assert np.allclose(phys[geom], slide_directions(output.lift, i)[geom])


def test_sweeps_cover_fig9(output: ReplayOutput) -> None:
    assert output.sweeps is not None
    mus = {(r.mu, r.mg) for r in output.sweeps["mu"]}
    mgs = {(r.mu, r.mg) for r in output.sweeps["mg"]}
    assert mus == {(m, 2.0) for m in SWEEP_MUS} and mgs == {(0.3, g) for g in SWEEP_MGS}
    assert all(r.variant == "L" for r in (*output.sweeps["mu"], *output.sweeps["mg"]))
    rows = _rows(output.files["lift-sweeps.csv"])
    assert len(rows) == (len(SWEEP_MUS) + len(SWEEP_MGS)) * STATES
    # the (mu 0.3, mg 2) curve is in both sweeps: the `sweep` column tells the copies apart
    both = [r["sweep"] for r in rows if (r["mu"], r["mg"]) == ("0.3", "2.0")]
    assert sorted(both) == ["mg"] * STATES + ["mu"] * STATES
    # the (mu, mg) = (0.3, 1) sweep is the main run's L curve
    main_l = [r.result.tvmmp for r in output.records if r.variant == "L"]
    assert [r.result.tvmmp for r in output.sweeps["mg"] if r.mg == 1.0] == main_l


def test_cli_replay_writes_results(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    args = ["replay", "--out", str(tmp_path / "res"), "--states", "3", "--no-sweeps", "--quiet"]
    assert main([*args, "--contacts", "S", "--reading", "literal", "--mu", "0.4", "--mg", "2"]) == 0
    assert f"wrote {tmp_path / 'res' / 'lift.csv'}\n" in capsys.readouterr().out
    assert sorted(p.name for p in (tmp_path / "res").iterdir()) == [
        ".mjtvm.lock",
        "fig8.png",
        "lift.csv",
        "lift.json",
    ]
    rows = _rows(tmp_path / "res" / "lift.csv")
    assert {(r["variant"], r["reading"], r["mu"], r["mg"]) for r in rows} == {("S", "literal", "0.4", "2.0")}
    assert (
        main(
            ["replay", "--out", str(tmp_path / "np"), "--states", "2", "--no-sweeps", "--no-plots", "--quiet"]
        )
        == 0
    )
    assert sorted(p.name for p in (tmp_path / "np").iterdir()) == [".mjtvm.lock", "lift.csv", "lift.json"]


@pytest.mark.parametrize(
    ("option", "message"),
    [
        (["--states", "1"], "error: --states: expected an integer in [2, 10000], got '1'"),
        (["--contacts", "L,X"], "error: --contacts: expected distinct values among L,S"),
        (["--contacts", "L,L"], "error: --contacts:"),
        (["--mu", "-0.1"], "error: --mu: expected a number in [0, 100], got '-0.1'"),
        (["--mg", "nan"], "error: --mg: expected a number in [0, 1000000], got 'nan'"),
        (["--tvms-every", "-1"], "error: --tvms-every: expected an integer in [0, 10000]"),
        (["--hand", "robot"], "no variant 'robot'"),
        (["--grasp", "case9"], "error: case9: no such grasp file, and not a shipped grasp"),
    ],
)
def test_cli_replay_bad_options_exit_2(
    option: list[str], message: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["replay", "--out", str(tmp_path), "--quiet", *option]) == 2
    assert message in capsys.readouterr().err


def test_cli_replay_unwritable_out_and_argparse_errors(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    (tmp_path / "file").write_text("x")
    assert main(["replay", "--out", str(tmp_path / "file" / "sub"), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert err == f"error: --out: cannot create the folder (Not a directory): {tmp_path / 'file' / 'sub'}\n"
    assert main(["replay", "--out", str(tmp_path / "file"), "--quiet"]) == 2
    assert capsys.readouterr().err == f"error: --out: expected a folder, found a file: {tmp_path / 'file'}\n"
    assert main(["replay", "--reading", "sideways"]) == 2
    assert capsys.readouterr().err.splitlines() == [
        "error: --reading: expected distinct values among physical,literal or both, got 'sideways' "
        "(try 'mjtvm replay --help')"
    ]
    with pytest.raises(ParamError, match=r"^readings: "):
        run_replay(out=tmp_path, readings=())


def test_time_replay_reports_runs(tmp_path: Path) -> None:
    report = time_replay(repeats=1, num_states=2)
    assert len(report["runs_s"]) == 1 and math.isfinite(report["median_s"]) and report["median_s"] > 0
    assert set(report["last"]) == {"lift_s", "replay_s", "sweeps_s", "output_s"}


def test_default_replay_draws_the_readme_fig8(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """A plain `mjtvm replay` draws the README's Fig. 8: L, S literal (the paper's curve) and S physical,
    the same records as tests/jobs/data/fig8_default.csv (the rows behind docs/fig8_default.png,
    drawn by `mjtvm replay --no-sweeps`), labelled."""
    import mjtvm.jobs.replay as replay

    labels: list[str] = []
    plot = replay._plot

    def spy(curves, title, x="z"):  # type: ignore[no-untyped-def]
        if title.startswith("Fig. 8"):
            labels.extend(label for label, _, _ in curves)
        return plot(curves, title, x)

    monkeypatch.setattr(replay, "_plot", spy)
    assert main(["replay", "--out", str(tmp_path), "--no-sweeps", "--quiet"]) == 0
    assert labels == [
        "L-points",
        "S-points, physical reading (what the physics supports)",
        "S-points, literal reading (the paper's Fig. 8)",
    ]
    got = _rows(tmp_path / "lift.csv")
    shown = _rows(Path(__file__).resolve().parent / "data" / "fig8_default.csv")
    assert [(r["variant"], r["reading"], r["state"]) for r in got] == [
        (r["variant"], r["reading"], r["state"]) for r in shown
    ]
    assert len(shown) == 90 and {r["reading"] for r in shown} == {"", "physical", "literal"}
    for a, b in zip(got, shown, strict=True):
        for key, value in b.items():
            if key.startswith(("alpha", "tvmmp", "z")) and value:
                assert float(a[key]) == pytest.approx(float(value), rel=1e-7, abs=1e-12), key
            elif not key.startswith(("alpha", "tvmmp", "z", "s")):
                assert a[key] == value, key


def test_a_grasp_of_ones_own_writes_its_own_conditions(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """`mjtvm replay --grasp FILE`: the grasp's mu and weight, its hand, its contact types in the
    titles, and the paper's Fig. 9 sweeps only with --sweeps."""
    import mjtvm.jobs.replay as replay

    titles: list[str] = []
    monkeypatch.setattr(replay, "_plot", lambda curves, title, x="z": titles.append(title) or b"png")
    grasp = Path(__file__).resolve().parents[2] / "models" / "allegro" / "allegro-ik.toml"  # every tip F
    args = ["replay", "--grasp", str(grasp), "--states", "2", "--quiet"]
    assert main([*args, "--out", str(tmp_path / "own")]) == 0
    assert sorted(p.name for p in (tmp_path / "own").iterdir()) == [
        ".mjtvm.lock",
        "fig8.png",
        "lift.csv",
        "lift.json",
    ]
    rows = _rows(tmp_path / "own" / "lift.csv")
    assert {(r["scenario"], r["hand"], r["mu"]) for r in rows} == {
        ("allegro-ik", "allegro_right_hand", "0.6")
    }
    assert {round(float(r["mg"]), 9) for r in rows} == {round(0.1 * 9.81, 9)}
    doc = json.loads((tmp_path / "own" / "lift.json").read_text(encoding="utf-8"))
    assert doc["hand"] == "allegro_right_hand" and doc["sweeps"] is None
    assert titles == [
        "TVMMP along the lift: allegro-ik, every finger an F-point, $\\mu$ = 0.6, $mg$ = 0.981 N"
    ]
    titles.clear()
    assert main([*args, "--sweeps", "--no-plots", "--out", str(tmp_path / "swept")]) == 0
    assert (tmp_path / "swept" / "lift-sweeps.csv").exists() and titles == []
    assert main([*args, "--sweeps", "--out", str(tmp_path / "figs")]) == 0
    assert [t.split(",")[1:2] for t in titles] == [[" every finger an F-point"]] * 3
    assert not any("L-points" in t for t in titles)


def test_the_paper_grasps_sweep_by_default(monkeypatch: pytest.MonkeyPatch) -> None:
    import mjtvm.jobs.replay as replay

    assert replay.paper_hand("case2") == "default" and replay.paper_hand("case1-s-humanlike") == "humanlike"
    assert replay.paper_hand("gripper3-box") is None and replay.paper_hand("case2-mine") is None
    assert replay.paper_hand("humanlike") is None
