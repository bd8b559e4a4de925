"""``--limit-horizon METRES`` on every command that solves Problem 2 from a grasp (issue 32).

The Robotiq 2F-85 grasp is the case where the horizon decides the number: both couplers
reach their stop after 0.99999 mm of lift, inside the default 1 mm horizon, so its TVMMP is
0 by default and 0.0714 at a horizon of 0 (on-limit rows only) or 0.999 mm
(``docs/joint-limits.md``, "Effect on the shipped grasps").
"""

from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np
import pytest

from mjtvm.cli import main

GRASP = "robotiq_2f85-sphere"
TVMMP = 0.0714  # within the horizon's edge: the on-limit-only number


def _replay_state0(tmp_path: Path, *horizon: str) -> tuple[float, dict[str, object]]:
    out = tmp_path / ("replay" + "".join(horizon))
    words = ["replay", "--grasp", GRASP, "--states", "2", "--no-plots", "--no-sweeps", "--quiet"]
    assert main([*words, "--out", str(out), *horizon]) == 0
    with (out / "lift.csv").open(newline="") as f:
        rows = list(csv.DictReader(f))
    return float(rows[0]["tvmmp"]), json.loads((out / "lift.json").read_text())


def test_replay_takes_the_horizon(tmp_path: Path) -> None:
    default, doc = _replay_state0(tmp_path)
    assert default == 0.0 and doc["limit_horizon"] is None
    for h in ("0", "0.000999"):
        tvmmp, doc = _replay_state0(tmp_path, "--limit-horizon", h)
        assert tvmmp == pytest.approx(TVMMP, abs=1e-4)
        assert doc["limit_horizon"] == float(h)


def test_sweep_takes_the_horizon_and_resumes_only_its_rows(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    words = [
        "sweep",
        "--grasp",
        GRASP,
        "--states",
        "2",
        "--state-indices",
        "0",
        "--quiet",
        "--out",
        str(tmp_path),
    ]

    def row() -> dict[str, object]:
        rows = json.loads((tmp_path / "sweep.json").read_text())
        assert len(rows) == 1
        return dict(rows[0])

    assert main(words) == 0
    assert row()["tvmmp"] == 0.0 and row()["limit_horizon"] is None
    # a resumed run with another horizon solves its point again: the horizon is part of the point
    assert main([*words, "--resume", "--limit-horizon", "0"]) == 0
    assert row()["tvmmp"] == pytest.approx(TVMMP, abs=1e-4) and row()["limit_horizon"] == 0.0
    assert main([*words, "--limit-horizon", "0.000999"]) == 0
    assert row()["tvmmp"] == pytest.approx(TVMMP, abs=1e-4)
    capsys.readouterr()


def test_rank_takes_the_horizon_and_its_digest(tmp_path: Path) -> None:
    from mjtvm.paper_hand.scenario import load_scenario

    qpos = np.asarray(load_scenario(GRASP).data.qpos)  # the grasp file's own configuration
    dataset = tmp_path / "one.npz"
    np.savez(dataset, qpos=qpos[None], id=np.array(["g0"]))
    rows = {}
    for h in ((), ("--limit-horizon", "0"), ("--limit-horizon", "0.000999")):
        out = tmp_path / ("rank" + "".join(h))
        assert main(["rank", GRASP, str(dataset), "--no-plots", "--quiet", "--out", str(out), *h]) == 0
        rows[h] = json.loads((out / "rank.json").read_text())[0]
    default, zero, below = rows.values()
    assert default["tvmmp"] == 0.0 and "limits" in default["reason"]
    assert zero["tvmmp"] == pytest.approx(TVMMP, abs=1e-4) and below["tvmmp"] == pytest.approx(
        TVMMP, abs=1e-4
    )
    # --resume must not keep the rows of another horizon
    assert len({default["inputs"], zero["inputs"], below["inputs"]}) == 3


def test_verify_takes_the_horizon(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    words = ["verify", "--grasp", GRASP, "--states", "1", "--contacts", "L", "--no-plots", "--quiet"]

    def rows(*h: str) -> list[dict[str, str]]:
        out = tmp_path / ("verify" + "".join(h))
        assert main([*words, "--out", str(out), *h]) == 0
        with (out / "verify.csv").open(newline="") as f:
            return list(csv.DictReader(f))

    default = rows()
    assert float(default[0]["alpha_lp"]) == 0.0 and default[0]["lp_note"] == ""
    zero = rows("--limit-horizon", "0")
    assert float(zero[0]["alpha_lp"]) == pytest.approx(TVMMP, abs=1e-4)
    assert "joint-limit horizon 0 m (--limit-horizon)" in zero[0]["lp_note"]
    capsys.readouterr()


def test_tvms_refuses_the_horizon_in_one_line(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["tvms", GRASP, "--limit-horizon", "0"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1
    assert err.startswith("error: --limit-horizon: not an option of tvms: Problem 1 has no travel horizon")
