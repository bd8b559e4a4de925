"""`mjtvm solve` says why an alpha is 0: the diagnosis in the JSON and one line on stderr."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from mjtvm.cli import main
from mjtvm.core.state_file import state_to_dict
from tests.core.test_diagnosis import A, link_point, state


def test_solve_prints_why_an_alpha_is_0(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Two sticking points on one rigid link lock the straight lift (tests/core/test_diagnosis.py)."""
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
