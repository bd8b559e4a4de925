"""The physics check of one state on a user's grasp (issue 25): a mesh object, a coupled hand and a
grasp file without a [lift], each checked once (every finger an F-point: one run, not three)."""

from __future__ import annotations

import csv
import subprocess
import sys
from pathlib import Path

import pytest

MODELS = Path(__file__).resolve().parents[2] / "models"
SHORT = ("--startup", "0.001", "--window", "0.002", "--no-plots", "--quiet")


def _verify(out: Path, *args: str) -> tuple[str, list[dict[str, str]]]:
    cmd = [sys.executable, "-m", "mjtvm.cli", "verify", *args, *SHORT, "--out", str(out)]
    proc = subprocess.run(cmd, capture_output=True, text=True, check=False)
    assert proc.returncode == 0, proc.stderr
    with (out / "verify.csv").open(newline="", encoding="utf-8") as f:
        return proc.stdout, list(csv.DictReader(f))


def _checked(rows: list[dict[str, str]]) -> None:
    """Every pair held at rest and checked: alpha_sim in [0, 2 alpha_kl], a verdict in words."""
    for r in rows:
        assert r["status"] == "optimal" and r["held"] == "True" and r["verdict"], r
        assert float(r["hold_reach"]) <= 5e-4
        assert 0.0 <= float(r["alpha_sim"]) <= 2.0 * float(r["alpha_lp"]) + 1e-12
        # a ratio outside [0.9, 1.05] carries its cause; one inside, or none (alpha_kl = 0), none
        ratio = float(r["ratio"])
        assert bool(r["cause"]) == (ratio == ratio and not 0.9 <= ratio <= 1.05), r


def test_one_state_of_the_mesh_object_grasp(tmp_path: Path) -> None:
    stdout, rows = _verify(tmp_path, "--grasp", "allegro-jenga", "--states", "1")
    assert {r["run"] for r in rows} == {"L"} and {r["state"] for r in rows} == {"0"}
    assert len(rows) == 6  # the six RVDS directions of the grasp file, one run: all F-points
    assert [line.split(":")[0] for line in stdout.splitlines()[:2]] == ["L", "L verdicts"]
    _checked(rows)


def test_one_state_of_a_coupled_hand(tmp_path: Path) -> None:
    """The Robotiq 2F-85: one actuator drives the linkage closed by MuJoCo's equality constraints."""
    _stdout, rows = _verify(tmp_path, "--grasp", "robotiq_2f85-sphere", "--states", "1")
    assert {r["run"] for r in rows} == {"L"} and len(rows) == 2  # its two RVDS vertices
    _checked(rows)
    assert all(
        r["verdict"].startswith(
            ("torque limit at actuator", "speed edge at actuator", "twist error", "passes", "slip")
        )
        for r in rows
    )


def test_a_grasp_file_without_a_lift_is_checked_at_its_own_state(tmp_path: Path) -> None:
    text = (MODELS / "allegro" / "allegro-ik.toml").read_text(encoding="utf-8")
    text = text[: text.index("[lift]")].replace(
        'model = "allegro_right_hand.xml"', f'model = "{MODELS / "allegro" / "allegro_right_hand.xml"}"'
    )
    grasp = tmp_path / "grasp.toml"
    grasp.write_text(text, encoding="utf-8")
    _stdout, rows = _verify(tmp_path, "--grasp", str(grasp))  # --states 30 by default: one state
    assert {r["state"] for r in rows} == {"0"} and {r["run"] for r in rows} == {"L"}
    _checked(rows)


def test_states_must_be_a_positive_count(tmp_path: Path) -> None:
    cmd = [sys.executable, "-m", "mjtvm.cli", "verify", "--states", "0", "--out", str(tmp_path)]
    proc = subprocess.run(cmd, capture_output=True, text=True, check=False)
    assert proc.returncode == 2
    assert (
        proc.stderr.strip().splitlines()[-1].startswith("error: --states: expected an integer in [1, 10000]")
    )


@pytest.mark.parametrize("grasp", ["case2"])
def test_a_grasp_with_l_fingers_keeps_its_variants(grasp: str) -> None:
    from mjtvm.jobs import verify

    lift = verify.checked_lift(grasp, 2)
    assert lift.num_states == 2
    assert verify.present_runs(lift, verify.RUNS) == list(verify.RUNS)


def _servo_grasp(tmp_path: Path, datasheet: str) -> Path:
    """allegro-ik with every joint a DYNAMIXEL XH430-W350 (the servo datasheet form)."""
    text = (MODELS / "allegro" / "allegro-ik.toml").read_text(encoding="utf-8")
    text = text.replace(
        'model = "allegro_right_hand.xml"', f'model = "{MODELS / "allegro" / "allegro_right_hand.xml"}"'
    )
    text = text.replace('datasheet = "maxon_re25_20w"\ngear_ratio = 27', f"datasheet = {datasheet}")
    assert f"datasheet = {datasheet}" in text
    grasp = tmp_path / "servo.toml"
    grasp.write_text(text, encoding="utf-8")
    return grasp


@pytest.mark.parametrize(
    ("datasheet", "rotor"),
    [
        ('"dynamixel_xh430_w350"', 0.0),  # the shipped sheet publishes no rotor inertia
        (
            "{ voltage_V = 12.0, stall_torque_Nm = 3.4, no_load_speed_rpm = 30.0, rotor_inertia_kgm2 = 0.002 }",
            0.002,
        ),
    ],
)
def test_servo_ranges_with_the_motor_of_their_datasheet(tmp_path: Path, datasheet: str, rotor: float) -> None:
    """The servo form's triangle range (a polygon) with the <dcmotor> of the same line; the
    rotor inertia is the sheet's (figures at the output: gear 1), stated in every row."""
    _stdout, rows = _verify(tmp_path, "--grasp", str(_servo_grasp(tmp_path, datasheet)), "--states", "1")
    assert len(rows) == 6
    _checked(rows)
    assert {float(r["rotor_inertia"]) for r in rows} == {rotor}
