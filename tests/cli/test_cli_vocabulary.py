"""One CLI vocabulary (issue 33): ``solve --mu/--mg/--quiet``, ``rank --grasp``,
``verify --hand`` mean what the other commands' options of those names mean."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from mjtvm.cli import main
from mjtvm.formats.state_file import state_to_dict
from tests.problem2.test_diagnosis import A, link_point, state


def _solve(capsys: pytest.CaptureFixture[str], *argv: str) -> float:
    assert main(["solve", "case2", "--no-witnesses", *argv]) == 0
    return float(json.loads(capsys.readouterr().out)["tvmmp"])


def test_solve_mu_and_mg_are_the_grasps_friction_and_weight(capsys: pytest.CaptureFixture[str]) -> None:
    """case2 (mu 0.3, mg 1 N): more friction, a lighter object: a larger TVMMP; each value is the
    library's for the grasp with those options (what replay and export-state load)."""
    from mjtvm import tvmmp
    from mjtvm.paper_hand.scenario import load_scenario

    base = _solve(capsys)
    assert base == pytest.approx(tvmmp(load_scenario("case2").state()).tvmmp, rel=1e-9)
    mu = _solve(capsys, "--mu", "0.5")
    assert mu == pytest.approx(tvmmp(load_scenario("case2", mu=0.5).state()).tvmmp, rel=1e-9)
    mg = _solve(capsys, "--mg", "2")
    assert mg == pytest.approx(tvmmp(load_scenario("case2", mg=2.0).state()).tvmmp, rel=1e-9)
    assert _solve(capsys, "--mu", "0.1") < base < mu
    assert mg < base < _solve(capsys, "--mg", "0.5")
    assert _solve(capsys, "--mu", "0.3", "--mg", "1") == pytest.approx(base, rel=1e-9)


@pytest.mark.parametrize("option", ["--mu", "--mg"])
def test_solve_refuses_mu_and_mg_for_a_state_file(option: str, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["solve", option, "0.5"]) == 2  # the shipped pinch.json
    (line,) = capsys.readouterr().err.splitlines()
    assert line.startswith(f"error: {option}: applies to a grasp")


def _untimed(doc: dict[str, object]) -> dict[str, object]:
    return {k: v for k, v in doc.items() if k != "timings"}


def test_solve_quiet_empties_stderr_and_keeps_stdout(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The locked state of tests/cli/test_solve_diagnosis.py warns on stderr; --quiet does not."""
    path = tmp_path / "locked.json"
    path.write_text(json.dumps(state_to_dict(state([link_point("tip", A), link_point("mid", 0.03)]))))
    assert main(["solve", str(path)]) == 0
    loud = capsys.readouterr()
    assert loud.err.startswith("mjtvm: warning: alpha[0][0] = 0")
    assert main(["solve", str(path), "--quiet"]) == 0
    quiet = capsys.readouterr()
    assert quiet.err == ""
    assert _untimed(json.loads(quiet.out)) == _untimed(json.loads(loud.out))


def test_rank_takes_grasp_as_option_or_argument_not_both(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    import mjtvm.jobs.rank_files as rank_files

    seen = []
    monkeypatch.setattr(rank_files, "run_rank_files", lambda run, emit: seen.append(run) or [])
    a, b = tmp_path / "a.npz", tmp_path / "b.npz"
    a.write_bytes(b""), b.write_bytes(b"")
    assert main(["rank", "--grasp", "case2", str(a), str(b), "--out", str(tmp_path)]) == 0
    assert main(["rank", "case2", str(a), str(b), "--out", str(tmp_path)]) == 0
    assert main(["rank", str(a), "--grasp", "case2", "--out", str(tmp_path)]) == 0
    assert [(r.grasp, r.datasets) for r in seen] == [("case2", (str(a), str(b)))] * 2 + [("case2", (str(a),))]
    assert main(["rank", "case1", str(a), "--grasp", "case2", "--out", str(tmp_path)]) == 2
    (line,) = capsys.readouterr().err.splitlines()
    assert line == "error: --grasp: give GRASP or --grasp, not both (try 'mjtvm rank --help')"


def test_verify_hand_is_replays(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """--hand humanlike: the paper's grasp of that hand; for another grasp a one-line refusal,
    replay's (tests/cli: replay refuses it the same)."""
    from mjtvm.cli import verify_parser
    from mjtvm.grasp.resolve.variants import with_hand

    args = verify_parser().parse_args(["--grasp", "case2", "--hand", "humanlike"])
    assert args.hand == "humanlike" and with_hand(args.grasp, args.hand) == "case2-humanlike"
    assert main(["verify", "--grasp", "allegro-ik", "--hand", "humanlike", "--out", str(tmp_path)]) == 2
    (line,) = capsys.readouterr().err.splitlines()
    assert line == "error: variant: applies to the shipped scenarios (case1, case1-s, case2) only"
