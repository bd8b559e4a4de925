"""``mjtvm verify`` checks what ``mjtvm solve`` reports (issue 32): its alpha_lp is solve's alpha on
the grasp's own state, pair by pair, on every shipped grasp and on mesh-object grasps with REFS =
the weight; the refusals about the weight name what to change."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import mujoco
import numpy as np
import pytest

from mjtvm.errors import ParamError
from mjtvm.grasp.resolve.file import load_grasp
from mjtvm.jobs import verify
from mjtvm.jobs.replay import grasp_defaults
from mjtvm.lift.states import lift_state
from mjtvm.physics.simulate import sim_model
from mjtvm.problem2.tvmmp import tvmmp

MODELS = Path(__file__).resolve().parents[2] / "models"
# Every shipped grasp file that solve solves (case1 and its humanlike hand have no RVDS:
# Problem 2 refuses them, in solve as in verify) and whose lift the check can build
# (case1-s: the lift's witness finds no contact normal for 'f3_link1', a refusal of its own;
# shadow_hand_5f_coupled-sphere: REFS beyond the weight, which verify refuses without --mg).
SHIPPED = sorted(
    str(p.relative_to(MODELS))
    for p in MODELS.glob("*/*.toml")
    if p.stem
    not in ("case1", "case1-humanlike", "case1-s", "case1-s-humanlike", "shadow_hand_5f_coupled-sphere")
)


def _solve_alpha(path: Path) -> tuple[np.ndarray, list[str]]:
    """alpha[0] and status[0] as ``mjtvm solve FILE`` reports them (its state, its tvmmp)."""
    res = tvmmp(load_grasp(path).state())
    return res.alpha[0], list(res.status[0])


def _verify_alpha(path: Path, run: str = "L") -> tuple[np.ndarray, list[str], dict[str, str]]:
    """alpha_lp and status of state 0 as ``mjtvm verify --grasp FILE`` computes them."""
    lift = verify.checked_lift(path, 1)
    mu, mg = grasp_defaults(lift.scenario, None, None)
    _state, res, fields = verify.verify_lp(lift, 0, run, mu=mu, mg=mg)
    assert not isinstance(res, Exception), res
    return res.alpha[0], list(res.status[0]), fields


@pytest.mark.parametrize("name", SHIPPED)
def test_verify_alpha_lp_is_solve_alpha_on_every_shipped_grasp(name: str) -> None:
    path = MODELS / name
    want, want_status = _solve_alpha(path)
    lift = verify.checked_lift(path, 1)
    mu, mg = grasp_defaults(lift.scenario, None, None)
    for run in verify.present_runs(lift, verify.RUNS):
        _state, res, fields = verify.verify_lp(lift, 0, run, mu=mu, mg=mg)
        assert not isinstance(res, Exception), res
        assert fields["lp_state"] == "grasp"
        if run == "L" or not fields["lp_note"]:  # the grasp's own contact types: solve's state
            assert fields["lp_note"] == "", fields
            assert list(res.status[0]) == want_status
            np.testing.assert_allclose(res.alpha[0], want, rtol=0.0, atol=1e-9)
        else:  # an S run retypes the file's L fingers: the note says so
            assert f"run {run} types" in fields["lp_note"]


def _gap_grasp(tmp_path: Path, opened: float) -> Path:
    """allegro-jenga (convex mesh pieces) at its IK configuration written out as qpos, the ring
    finger's distal joint opened by ``opened`` rad (a gap of ~0.1 mm at its tip, below the
    file's ``contact_tolerance`` of 1 mm): a contact solve counts that the lift's touching
    test (1 um) did not."""
    grasp = load_grasp(MODELS / "objects" / "allegro-jenga.toml")
    qpos = {}
    for j in grasp.joints:
        jid = mujoco.mj_name2id(grasp.model, mujoco.mjtObj.mjOBJ_JOINT, j)
        qpos[j] = float(grasp.data.qpos[grasp.model.jnt_qposadr[jid]])
    qpos["rfj3"] -= opened
    text = (MODELS / "objects" / "allegro-jenga.toml").read_text(encoding="utf-8")
    text = text.replace(
        'model = "allegro_jenga.xml"', f'model = "{MODELS / "objects" / "allegro_jenga.xml"}"'
    )
    text = text.replace("contact_tolerance = 1e-4", "contact_tolerance = 1e-3")
    a, b = text.index("[configuration.ik]"), text.index("[[contacts]]")
    config = "[configuration.qpos]\n" + "\n".join(f"{k} = {v!r}" for k, v in qpos.items()) + "\n\n"
    path = tmp_path / "jenga-gap.toml"
    path.write_text(text[:a] + config + text[b:], encoding="utf-8")
    return path


def test_a_mesh_grasp_with_a_finger_at_a_gap_is_feasible_in_verify_as_in_solve(tmp_path: Path) -> None:
    """Before: verify's state dropped the ring finger (3 contacts) and every pair was infeasible,
    while solve had 4 contacts and every pair optimal."""
    path = _gap_grasp(tmp_path, 0.01)
    grasp = load_grasp(path)
    lift = verify.checked_lift(path, 1)
    gap = next(r["distance"] for r in grasp.contact_report() if "rf_tip" in str(r["selection"]))
    assert 1e-6 < gap < 1e-3  # beyond the lift's touching test, within the file's tolerance
    want, want_status = _solve_alpha(path)
    got, status, fields = _verify_alpha(path)
    assert want_status == status == ["optimal"] * 6
    np.testing.assert_allclose(got, want, rtol=0.0, atol=1e-9)
    assert fields == {"lp_state": "grasp", "lp_note": ""}
    assert len(lift_state(lift, 0, mu=0.6).contacts) == len(grasp.state().contacts) == 4


def test_the_lift_state_carries_the_weight_through_the_centre_of_mass() -> None:
    """A mesh object's centre of mass is off its body origin: the REFS have a moment about it
    (before: verify's REFS were [0, 0, -mg, 0, 0, 0], alpha_lp 0.029403 vs solve's 0.029372)."""
    path = MODELS / "objects" / "allegro-jenga.toml"
    grasp = load_grasp(path)
    lift = verify.checked_lift(path, 1)
    assert np.linalg.norm(grasp.refs[0, 3:]) > 1e-3  # N m: the moment of the weight
    for mg in (None, 2.5):
        refs = lift_state(lift, 0, mg=mg).refs
        want = grasp.refs if mg is None else grasp.refs * (2.5 / np.linalg.norm(grasp.refs[0, :3]))
        np.testing.assert_allclose(refs, want, rtol=1e-12, atol=1e-15)


def test_the_note_says_what_verify_changes(tmp_path: Path) -> None:
    path = MODELS / "objects" / "allegro-jenga.toml"
    lift = verify.checked_lift(path, 1)
    _state, res, fields = verify.verify_lp(lift, 0, "L", mu=0.4, mg=2.0, preload=0.5)
    assert fields["lp_state"] == "grasp"
    note = fields["lp_note"]
    assert "mu 0.4 (--mu)" in note and "mg 2 N (--mg)" in note and "(--preload)" in note
    assert not isinstance(res, Exception)


# ------------------------------------------------------------------ the refusals about the weight
def _no_gravity_grasp(tmp_path: Path, refs: str) -> Path:
    xml = (MODELS / "gripper3" / "gripper3.xml").read_text(encoding="utf-8")
    xml = xml.replace('<option timestep="0.002"', '<option gravity="0 0 0" timestep="0.002"')
    assert 'gravity="0 0 0"' in xml
    (tmp_path / "gripper3.xml").write_text(xml, encoding="utf-8")
    text = (MODELS / "gripper3" / "gripper3-box.toml").read_text(encoding="utf-8")
    path = tmp_path / "nograv.toml"
    text = text.replace('name = "gripper3-box"', 'name = "nograv"').replace("[refs]\nweight = true", refs)
    assert refs in text
    path.write_text(text, encoding="utf-8")
    return path


def _cli(*args: str) -> subprocess.CompletedProcess[str]:
    cmd = [sys.executable, "-m", "mjtvm.cli", *args]
    return subprocess.run(cmd, capture_output=True, text=True, check=False)


def test_verify_mg_on_a_scene_without_gravity_is_one_line_naming_the_gravity(tmp_path: Path) -> None:
    path = _no_gravity_grasp(tmp_path, "[refs]\nwrenches = [[0, 0, -1, 0, 0, 0]]")
    out = tmp_path / "out"
    proc = _cli(
        "verify",
        "--grasp",
        str(path),
        "--states",
        "1",
        "--mg",
        "1",
        "--no-plots",
        "--quiet",
        "--out",
        str(out),
    )
    assert proc.returncode == 2, proc.stderr
    lines = [x for x in proc.stderr.splitlines() if "warning" not in x]
    assert len(lines) == 1 and "Traceback" not in proc.stderr
    assert "no gravity" in lines[0] and '<option gravity="0 0 -9.81"/>' in lines[0]
    # without --mg: the REFS (a wrench) are not the weight alone, and the refusal says how to give it
    proc = _cli("verify", "--grasp", str(path), "--states", "1", "--no-plots", "--quiet", "--out", str(out))
    assert proc.returncode == 2 and "Traceback" not in proc.stderr
    assert "give the weight with --mg" in proc.stderr and "[refs]" in proc.stderr


def test_each_refusal_about_the_weight_names_what_to_change(tmp_path: Path) -> None:
    nograv = load_grasp(_no_gravity_grasp(tmp_path, "[refs]\nwrenches = [[0, 0, -1, 0, 0, 0]]"))
    with pytest.raises(ParamError, match=r"mg: .*no gravity.*<option gravity="):
        grasp_defaults(nograv, 0.5, 1.0)
    with pytest.raises(ParamError, match=r"mg: .*not its weight alone: give the weight with --mg .*\[refs\]"):
        grasp_defaults(nograv, 0.5, None)
    text = (MODELS / "gripper3" / "gripper3-box.toml").read_text(encoding="utf-8")
    text = text.replace('model = "gripper3.xml"', f'model = "{MODELS / "gripper3" / "gripper3.xml"}"')
    refs = "[refs]\nweight = false\nwrenches = [[0, 0, -1, 0, 0, 0]]"
    (tmp_path / "w.toml").write_text(text.replace("[refs]\nweight = true", refs), encoding="utf-8")
    noweight = load_grasp(tmp_path / "w.toml")
    with pytest.raises(
        ParamError, match=r"mg: .*weight = false.*--mg cannot replace it; set \[refs\] weight = true"
    ):
        grasp_defaults(noweight, 0.5, 1.0)
    # a contact's own mu overrides the file's: the rollouts simulate one coefficient
    (tmp_path / "m.toml").write_text(text.replace('type = "F"', 'type = "F"\nmu = 0.9', 1), encoding="utf-8")
    multi = load_grasp(tmp_path / "m.toml")
    assert multi.default_mu is None and sorted(set(multi.mu.values())) == [0.5, 0.9]
    with pytest.raises(ParamError, match=r"mu: .*no single friction coefficient: give one with --mu"):
        grasp_defaults(multi, None, None)
    model = mujoco.MjModel.from_xml_string(
        '<mujoco><option gravity="0 0 0"/><worldbody><body name="object"><freejoint/>'
        '<geom size="0.01" mass="0.1"/></body></worldbody></mujoco>'
    )
    with pytest.raises(ParamError, match=r"mg: the object has no weight to scale .*<option gravity="):
        sim_model(model, {}, mu=0.5, mg=1.0)


def test_an_infeasible_row_says_why() -> None:
    """allegro-jenga with mu = 0.05 (its 0.6 in the file): the fingertips' cones cannot hold the
    block, whatever the torques; the rows carry the diagnosis solve prints, which names the
    direction and a contact whose friction would hold it."""
    lift = verify.checked_lift(MODELS / "objects" / "allegro-jenga.toml", 1)
    _state, res, fields = verify.verify_lp(lift, 0, "L", mu=0.05, mg=1.1772)
    assert not isinstance(res, Exception)
    assert list(res.status[0]) == ["infeasible"] * 6 and "mu 0.05 (--mu)" in fields["lp_note"]
    (d,) = res.diagnosis
    assert d.cause == "balance" and d.relief and all(c.endswith("/geom1") for c, _ in d.relief)
    reason = verify.pair_reason(res, 0)  # the row's reason column
    assert reason == d.message and "a net force along (" in reason and "balanced with '" in reason
