"""`mjtvm solve` says why an alpha is 0: the diagnosis in the JSON and one line on stderr."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from mjtvm.cli import main
from mjtvm.formats.state_file import state_to_dict
from tests.problem2.test_diagnosis import A, link_point, state


def test_solve_prints_why_an_alpha_is_0(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Two sticking points on one rigid link lock the straight lift (tests/problem2/test_diagnosis.py)."""
    path = tmp_path / "locked.json"
    path.write_text(json.dumps(state_to_dict(state([link_point("tip", A), link_point("mid", 0.03)]))))
    assert main(["solve", str(path), "--no-witnesses"]) == 0
    out, err = capsys.readouterr()
    doc = json.loads(out)
    assert doc["tvmmp"] == 0.0 and doc["diagnosis"][0]["contacts"] == ["tip", "mid"]
    assert err == (
        "mjtvm: warning: alpha[0][0] = 0: the contacts 'tip' (F), 'mid' (F) lock the motion along RVDS "
        "vertex 0: their kinematic rows (J qd = G^T rdot, eq. 11-13) admit no joint speed for it; 'tip' and "
        "'mid' are sticking points moved by the same joints\n"
    )


def test_solve_prints_which_torque_limit_makes_a_pair_infeasible(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "weak.json"
    path.write_text(json.dumps(state_to_dict(state([link_point("tip", A)], g_f=3.0))))
    assert main(["solve", str(path), "--no-witnesses"]) == 0
    out, err = capsys.readouterr()
    assert json.loads(out)["diagnosis"][0]["joints"] == ["q"]
    assert err.startswith(
        "mjtvm: warning: REFS vertex 0 cannot be balanced: the torque limits of 'q' (needs 3.05 N m"
    )


def test_solve_says_which_way_a_vertex_is_unbalanced_and_what_relieves_it(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The tilted support of tests/problem2/test_diagnosis.py (normal 60 deg from vertical, mu 0.3):
    stderr names the vertex, the direction and the contact with the friction that holds it
    (tan 60 deg = 1.732, rounded up); the JSON has the same in direction and relief."""
    from mjtvm import Contact

    palm = Contact("palm", "F", [A, 0.0], [3.0**0.5 / 2.0, 0.5], [[0.0], [0.0]], mu=0.3)
    path = tmp_path / "tilted.json"
    path.write_text(json.dumps(state_to_dict(state([palm], g_f=0.0))))
    assert main(["solve", str(path), "--no-witnesses"]) == 0
    out, err = capsys.readouterr()
    (d,) = json.loads(out)["diagnosis"]
    assert d["relief"] == [{"contact": "palm", "change": "mu >= 1.74"}] and len(d["direction"]) == 3
    (line,) = err.splitlines()
    assert line.startswith("mjtvm: warning: REFS vertex 0 cannot be balanced by any forces of the contacts")
    assert "a net force along (" in line and line.endswith("balanced with 'palm' mu >= 1.74")


def test_a_torque_limit_names_the_direction_too() -> None:
    r"""One F-point under the object (normal (0, 1)) and a weight of 30 N: its force (0, 30)
    needs tau = A 30 = 1.5 N m > T_max: cause ranges; the escape is straight down, the
    weight's direction."""
    from mjtvm import tvmmp

    (d,) = tvmmp(state([link_point("tip", A)], refs=[[0.0, -30.0, 0.0]], g_f=0.0), diagnose=True).diagnosis
    assert (d.cause, d.joints) == ("ranges", ("q",))
    assert d.message.endswith(
        "bind (eq. 19-20); within those limits: a net force along (0, -1) (the REFS vertex's own "
        "direction) that no admissible contact force opposes"
    )
    assert d.direction[1] == pytest.approx(-1.0, abs=1e-6)
