"""The hold test at rest (mjtvm.physics.hold): a grasp that holds passes it, a grasp that does not
is stopped with one line naming how far the object moved and the contact that lets go."""

from __future__ import annotations

import subprocess
import sys
from typing import Any

import mujoco
import numpy as np
import pytest

from mjtvm.errors import ParamError
from mjtvm.jobs import verify
from mjtvm.lift.states import lift_state
from mjtvm.physics.hold import hold_test
from mjtvm.physics.simulate import SimSettings, sim_model
from mjtvm.physics.witness import witness_drive
from mjtvm.problem2.tvmmp import tvmmp


@pytest.fixture(scope="module")
def case2() -> tuple[Any, Any, Any]:
    lift = verify.cached_lift("case2", 2)
    state = lift_state(lift, 0, variant="L", mu=0.3, mg=1.0)
    res = tvmmp(state)
    drive = witness_drive(state, 0, 0, float(res.alpha[0, 0]), 0.0)
    return lift, state, drive


def _model(lift: Any, state: Any) -> mujoco.MjModel:
    types = {c.name.split("#")[0]: c.type for c in state.contacts}
    return sim_model(verify.motor_model(lift.scenario), types, mu=0.3, mg=1.0)


def test_the_paper_grasp_holds_at_rest(case2: Any) -> None:
    lift, state, drive = case2
    out = hold_test(_model(lift, state), lift.qpos[0], drive)
    st = SimSettings()
    assert out.duration == pytest.approx(st.settle + st.startup + st.window)
    assert out.held and out.bound == st.lost_gap
    assert out.drift < 1e-4 and out.reach < 1e-4  # the contacts' compression (m), far below 0.5 mm
    forces = {c.label: c.force_end for c in out.contacts}
    # the witness at alpha = 0 presses fingers 1-3 on; MuJoCo's forces balance the 1 N weight
    assert all(forces[f] > 0.5 for f in ("f1_tip", "f2_tip", "f3_tip")), forces


def test_a_grasp_with_too_little_friction_in_the_simulation_is_not_held(case2: Any) -> None:
    """The witness forces balance the 1 N weight with mu = 0.3 (the LP's); the simulated
    fingers have mu = 0.05: the object slides out, and the contact that moved most is named."""
    lift, state, drive = case2
    types = {c.name.split("#")[0]: c.type for c in state.contacts}
    model = sim_model(verify.motor_model(lift.scenario), types, mu=0.05, mg=1.0)
    out = hold_test(model, lift.qpos[0], drive)
    assert not out.held and out.reach > 5e-4
    assert out.reach == pytest.approx(out.drift + out.speed * out.duration)
    lets_go = out.lets_go
    assert lets_go is not None and lets_go.moved == max(c.moved for c in out.contacts)
    assert lets_go.label in {"f1_tip", "f2_tip", "f3_tip", "f4_tip"}
    line = out.message()
    assert "\n" not in line
    assert line.startswith("does not hold at rest: in 37 ms the object moves ")
    assert f"; {lets_go.label} lets go: slides " in line


def test_a_longer_hold_is_asked_for_by_duration(case2: Any) -> None:
    lift, state, drive = case2
    out = hold_test(_model(lift, state), lift.qpos[0], drive, duration=0.01)
    assert out.duration == pytest.approx(0.01)
    with pytest.raises(ParamError, match=r"duration: expected a positive time"):
        hold_test(_model(lift, state), lift.qpos[0], drive, duration=0.0)


def _verify(*args: str) -> subprocess.CompletedProcess[str]:
    cmd = [sys.executable, "-m", "mjtvm.cli", "verify", *args, "--no-plots", "--quiet"]
    return subprocess.run(cmd, capture_output=True, text=True, check=False)


def test_verify_says_in_one_line_that_the_grasp_does_not_hold(tmp_path: Any) -> None:
    """The coupled Shadow grasp held by the least forces (``--hold-drive least``): the LP holds
    it, but at state 0 the first finger, on its friction cone in the witness, slides and the
    object leaves its contacts within a rollout's time (docs/physics-check.md)."""
    proc = _verify(
        "--grasp", "shadow_hand_coupled-sphere", "--states", "2", "--contacts", "L",
        "--hold-drive", "least", "--out", str(tmp_path),
    )  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    lines = [x for x in proc.stderr.splitlines() if "does not hold" in x]
    assert len(lines) >= 1, proc.stderr
    assert lines[0].startswith(
        "mjtvm verify: shadow_hand_coupled-sphere state 0 (L) does not hold at rest: in 37 ms"
    )
    assert " lets go: slides " in lines[0] and "not_held" in proc.stdout
    rows = verify_rows(tmp_path / "verify.csv")
    assert {r["held"] for r in rows if r["state"] == "0"} == {"False"}
    assert all(r["alpha_sim"] == "" for r in rows if r["state"] == "0")


def test_verify_holds_the_coupled_shadow_with_the_squeeze(tmp_path: Any) -> None:
    """The same state under ``--hold-drive auto`` (the default): the least forces let go, the
    squeeze and its position loop hold it (docs/physics-check.md#the-squeeze-hold), and every
    pair gets a ratio."""
    proc = _verify(
        "--grasp", "shadow_hand_coupled-sphere", "--states", "2", "--stride", "2", "--contacts", "L",
        "--out", str(tmp_path),
    )  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    assert "does not hold" not in proc.stderr
    rows = [r for r in verify_rows(tmp_path / "verify.csv") if r["state"] == "0"]
    assert rows and {(r["hold_drive"], r["held"]) for r in rows} == {("squeeze", "True")}
    assert all(float(r["hold_reach"]) < 5e-4 for r in rows)
    assert all(0.5 < float(r["ratio"]) < 1.1 for r in rows), [r["ratio"] for r in rows]


def test_verify_refuses_the_sum_tendon_shadow_for_the_lps_reason(tmp_path: Any) -> None:
    """The public models' sum tendon alone: the LP cannot hold the grasp (mjtvm.problem2.holding),
    so every row is infeasible with that reason and no rollout runs."""
    proc = _verify(
        "--grasp", "shadow_hand-sphere", "--states", "1", "--contacts", "L", "--out", str(tmp_path)
    )
    assert proc.returncode == 0, proc.stderr
    rows = verify_rows(tmp_path / "verify.csv")
    assert rows and all(r["status"] == "infeasible" for r in rows)
    assert all(r["reason"].startswith("REFS vertex 0 cannot be held at rest: the transmission") for r in rows)


def test_verify_on_a_holding_grasp_prints_no_hold_line(tmp_path: Any) -> None:
    proc = _verify("--grasp", "case2", "--states", "2", "--contacts", "L", "--out", str(tmp_path))
    assert proc.returncode == 0, proc.stderr
    assert "does not hold" not in proc.stderr and "not_held 0" in proc.stdout
    rows = verify_rows(tmp_path / "verify.csv")
    assert all(r["held"] == "True" and r["hold_drive"] == "least" for r in rows)  # auto: as before
    assert all(float(r["hold_drift"]) < 1e-4 for r in rows)
    assert np.all([float(r["alpha_sim"]) > 0 for r in rows])


def verify_rows(path: Any) -> list[dict[str, str]]:
    import csv

    with open(path, newline="", encoding="utf-8") as f:
        return list(csv.DictReader(f))
