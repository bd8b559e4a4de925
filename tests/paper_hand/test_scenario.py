"""The paper's scenarios (mjtvm.paper_hand.scenario): data files, contacts, and Case 1's claims (DIGEST section 6)."""

from __future__ import annotations

import importlib.util
import json
import tomllib
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from mjtvm.errors import ModelError
from mjtvm.formats.state_file import load_state
from mjtvm.grasp.resolve.file import shipped_grasps
from mjtvm.model.contacts import slide_unit
from mjtvm.model.state import GraspState
from mjtvm.paper_hand.hand import hand_mjcf, model_files
from mjtvm.paper_hand.placement import (
    finger1_tvmm_curve,
    make_documents,
    rule_posture,
    solve_variant,
    variant_model_text,
)
from mjtvm.paper_hand.scenario import (
    SCENARIOS,
    grasp_document,
    grasp_file_name,
    load_scenario,
    read_scenario,
    scenario_path,
)
from mjtvm.paper_hand.scenario import scenario_document as export
from mjtvm.problem2.assembly import grasp_map_transpose
from mjtvm.problem2.tvmmp import tvmmp
from tests.support.documents import format_document, format_toml

ROOT = Path(__file__).resolve().parents[2]
RANK_TOL = 1e-9  # singular values below this count as zero (the others are > 0.5, the zeros < 1e-14)
BETA = np.array([0.697, 0, -0.174, 0, 0.697, 0])  # the paper's, scaled by diag(10, 10, 10, 1, 1, 1)
SCALE = np.diag([10.0, 10, 10, 1, 1, 1])
VARIANTS = ("default", "humanlike")


@pytest.fixture(scope="module")
def generated() -> dict[str, dict[str, Any]]:
    return make_documents()


def _state(name: str, variant: str = "default") -> GraspState:
    """The state as a client sees it: through the exported mjtvm.state/1 document."""
    return load_state(json.loads(json.dumps(export(name, variant=variant))))


# ------------------------------------------------------------- kinematics helpers
def _stack(state: GraspState, names: list[str]) -> tuple[np.ndarray, np.ndarray]:
    """Stacked J_c (3L x M) and G_c^T (3L x 6) of the named contacts."""
    by_name = {c.name: c for c in state.contacts}
    jac = np.vstack([by_name[n].jacobian for n in names])
    gt = np.vstack([grasp_map_transpose(by_name[n].position, state.object_position) for n in names])
    return jac, gt


def _reachable(state: GraspState, names: list[str], basis: np.ndarray | None = None) -> np.ndarray:
    r"""Orthonormal basis (columns) of {rdot in range(basis) : exists qd, J_c qd = G_c^T rdot} (eq. 7).

    rdot = E z is reachable iff G_c^T E z lies in range(J_c), i.e. (I - U U^T) G_c^T E z = 0
    with U an orthonormal basis of range(J_c): a null space, taken by SVD with RANK_TOL.
    """
    e = np.eye(6) if basis is None else basis
    jac, gt = _stack(state, names)
    u, s, _ = np.linalg.svd(jac)
    u = u[:, : int((s > RANK_TOL * s[0]).sum())]
    k = (gt - u @ (u.T @ gt)) @ e
    _, sk, vt = np.linalg.svd(k)
    sk = np.r_[sk, np.zeros(e.shape[1] - len(sk))]
    assert np.all((sk < 1e-12) | (sk > 0.5)), f"no clear rank gap: {sk}"
    return e @ vt[int((sk > RANK_TOL).sum()) :].T


def _slide_translations(state: GraspState) -> tuple[np.ndarray, np.ndarray]:
    r"""Translations (omega = 0) allowed by the equalities with rho >= 0 (eq. 7, 13).

    Unknowns x = [qd (M); v (3); rho]: F rows J qd - G^T v = 0; S rows J qd - G^T v + rho s = 0
    (s the unit tangential slide direction: normal part 0, tangential part -rho s). Returns
    (basis of the translations with rho = 0, the translation at rho = 1 with its rho = 0 part
    removed): the allowed set is span(first) + {t * second, t >= 0}.
    """
    m = state.num_joints
    rows = []
    for c in state.contacts:
        assert c.type in ("F", "S")
        block = np.hstack(
            [c.jacobian, -grasp_map_transpose(c.position, state.object_position)[:, :3], np.zeros((3, 1))]
        )
        if c.type == "S":
            block[:, -1] = slide_unit(c)
        rows.append(block)
    a = np.vstack(rows)
    fixed = np.vstack([a, np.eye(m + 4)[-1]])  # rho = 0
    _, s, vt = np.linalg.svd(fixed)
    null = vt[int((s > RANK_TOL).sum()) :].T
    u, sv, _ = np.linalg.svd(null[m : m + 3])
    free = u[:, : int((sv > RANK_TOL).sum())]
    x = np.linalg.lstsq(fixed, np.r_[np.zeros(a.shape[0]), 1.0], rcond=None)[0]
    assert np.abs(a @ x).max() < 1e-12 and x[-1] == pytest.approx(1.0)
    v = x[m : m + 3]
    return free, v - free @ (free.T @ v)


# ------------------------------------------------------------------- the files
def _assert_close(a: Any, b: Any, where: str = "") -> None:
    if isinstance(a, dict):
        assert isinstance(b, dict) and list(a) == list(b), where
        for k in a:
            _assert_close(a[k], b[k], f"{where}.{k}")
    elif isinstance(a, list):
        assert isinstance(b, list) and len(a) == len(b), where
        for i, (x, y) in enumerate(zip(a, b)):
            _assert_close(x, y, f"{where}[{i}]")
    elif isinstance(a, (int, float)) and not isinstance(a, bool):
        assert isinstance(b, (int, float)) and abs(a - b) <= 1e-9, f"{where}: {a} != {b}"
    else:
        assert a == b, where


@pytest.mark.parametrize("name", SCENARIOS)
def test_files_equal_generator_output(generated: dict, name: str) -> None:
    committed = json.loads(scenario_path(name).read_text(encoding="utf-8"))
    _assert_close(committed, generated[name], name)


def test_make_scenarios_script(tmp_path: Path, generated: dict) -> None:
    spec = importlib.util.spec_from_file_location("make_scenarios", ROOT / "tools" / "make_scenarios.py")
    module = importlib.util.module_from_spec(spec)  # type: ignore[arg-type]
    spec.loader.exec_module(module)  # type: ignore[union-attr]
    assert module.main([str(tmp_path)]) == 0
    for name in SCENARIOS:
        text = (tmp_path / f"{name}.json").read_text(encoding="utf-8")
        assert json.loads(text) == json.loads(format_document(generated[name]))
        for variant in ("default", "humanlike"):
            file = grasp_file_name(name, variant)
            assert (tmp_path / file).read_text(encoding="utf-8") == format_toml(
                grasp_document(generated[name], variant)
            )


@pytest.mark.parametrize("name", SCENARIOS)
def test_grasp_files_equal_generator_output(generated: dict, name: str) -> None:
    """The shipped grasp files of the paper's cases are the generator's, to 1e-9 in every number."""
    for variant in ("default", "humanlike"):
        path = shipped_grasps()[grasp_file_name(name, variant)[: -len(".toml")]]
        committed = tomllib.loads(path.read_text(encoding="utf-8"))
        _assert_close(committed, grasp_document(generated[name], variant), f"{path.name}")


@pytest.mark.parametrize("name", SCENARIOS)
@pytest.mark.parametrize("variant", VARIANTS)
def test_variant_models_are_the_committed_ones(name: str, variant: str) -> None:
    doc = read_scenario(name)
    v = doc["variants"][variant]
    committed = (ROOT / "models" / "paper_hand" / v["model"]).read_text(encoding="utf-8")
    assert variant_model_text(doc, variant) == committed
    if v["model"] in model_files():  # the shared hands: the scenario uses them as they are
        assert committed == model_files()[v["model"]]
    else:  # Case 1's line-thin hand: the shared hand with other radii only
        assert "hand" in v and committed == hand_mjcf(
            finger_joints=v["finger_joints"], model_name=Path(v["model"]).stem, **v["hand"]
        )


@pytest.mark.parametrize("name", SCENARIOS)
@pytest.mark.parametrize("variant", VARIANTS)
def test_contacts_within_3_mm_of_the_paper(name: str, variant: str) -> None:
    doc = read_scenario(name)
    state = _state(name, variant)
    assert {c.name: c.type for c in state.contacts} == doc["contact_types"]
    centre, radius = np.array(doc["object_position"]), doc["object_radius"]
    np.testing.assert_allclose(state.object_position, centre)
    for c in state.contacts:
        (paper,) = [x["paper"] for x in doc["contacts"] if x["geom"] == c.name]
        on_sphere = centre + radius * (np.array(paper) - centre) / np.linalg.norm(np.array(paper) - centre)
        assert np.linalg.norm(c.position - on_sphere) <= 3e-3
        assert doc["variants"][variant]["solution"]["contacts"][c.name]["error_mm"] <= 3.0
        np.testing.assert_allclose(
            c.normal, (centre - c.position) / np.linalg.norm(centre - c.position), atol=1e-9
        )
    assert max(doc["variants"][variant]["solution"]["ik"]["residuals"].values()) <= 1e-10


def test_scenario_configuration_and_options() -> None:
    sc = load_scenario("case1")
    qpos = read_scenario("case1")["variants"]["default"]["solution"]["qpos"]
    for name, value in qpos.items():
        assert sc.data.qpos[sc.model.joint(name).qposadr[0]] == value
    assert sc.joints == tuple(f"f{i}_{j}" for i in (1, 3) for j in ("yaw0", "pitch0", "pitch1", "yaw1"))
    assert "palm" not in [c.name for c in sc.state().contacts]  # ignored: thin-link idealisation
    np.testing.assert_allclose(sc.state().refs, [[0, 0, -1, 0, 0, 0]])
    heavy = load_scenario("case2", mg=3.0, mu=0.5)
    state = heavy.state()
    np.testing.assert_allclose(state.refs, [[0, 0, -3, 0, 0, 0]])
    assert {c.mu for c in state.contacts if c.type == "F"} == {0.5}
    s_state = heavy.state(contact_types={"f2_tip": "S"}, slide_directions={"f2_tip": [0, 0, -1]})
    assert [c.type for c in s_state.contacts] == ["D", "F", "S", "F", "L"]
    with pytest.raises(ModelError, match="no variant 'robotic'"):
        load_scenario("case1", variant="robotic")
    with pytest.raises(ModelError, match="case9: no such grasp file, and not a shipped grasp"):
        load_scenario("case9")


# ------------------------------------------------------------- Case 1 claims
def test_case1_beta_is_the_one_in_plane_motion_of_finger_3() -> None:
    state = _state("case1")
    plane = np.eye(6)[:, [0, 2, 4]]  # xdot, zdot, omega_y
    motion = _reachable(state, ["f3_link1", "f3_link2"], plane)
    assert motion.shape == (6, 1)
    scaled = SCALE @ motion[:, 0]
    cos = abs(scaled @ BETA) / np.linalg.norm(scaled) / np.linalg.norm(BETA)
    assert np.degrees(np.arccos(min(cos, 1.0))) < 2.0  # 0.014 deg on the default model


def test_case1_tvms_spans_four_dimensions_and_translates_along_y_only() -> None:
    state = _state("case1")
    contacts = ["f1_tip", "f3_link1", "f3_link2"]
    assert [c.type for c in state.contacts] == ["F", "F", "F"]
    assert _reachable(state, contacts).shape[1] == 4
    translations = _reachable(state, contacts, np.eye(6)[:, :3])
    assert translations.shape == (6, 1)
    np.testing.assert_allclose(np.abs(translations[:, 0]), [0, 1, 0, 0, 0, 0], atol=1e-12)


def test_case1_s_translations_need_positive_xdot_and_zdot() -> None:
    """Kinematics: allowed translations = span(e_y) + {t d, t >= 0} with d_x, d_z > 0."""
    state = _state("case1-s")
    assert [c.type for c in state.contacts] == ["F", "S", "F"]
    free, d = _slide_translations(state)
    assert free.shape == (3, 1)
    np.testing.assert_allclose(np.abs(free[:, 0]), [0, 1, 0], atol=1e-12)
    assert d[0] > 0 and d[2] > 0 and abs(d[1]) < 1e-12


def _s_alphas(state: GraspState, d: np.ndarray) -> dict[str, float]:
    dh = d / np.linalg.norm(d)
    directions = {
        "d": dh,
        "d+y": dh + np.array([0, 1, 0]),
        "+y": [0, 1, 0],
        "-y": [0, -1, 0],
        "-d": -dh,
        "xdot<0": [-dh[0], 0, dh[2]],
        "zdot<0": [dh[0], 0, -dh[2]],
        "+x": [1, 0, 0],
        "+z": [0, 0, 1],
        "-x": [-1, 0, 0],
        "-z": [0, 0, -1],
        "x+z": [1, 0, 1],
    }
    rvds = np.array([np.r_[v, 0, 0, 0] for v in directions.values()], dtype=float)
    result = tvmmp(state.with_(rvds=rvds))
    assert result.feasible and set(result.status[0]) == {"optimal"}
    return dict(zip(directions, result.alpha[0]))


def test_case1_s_tvmmp_moves_only_with_positive_xdot_and_zdot() -> None:
    state = _state("case1-s")
    np.testing.assert_allclose(state.rvds, np.kron(np.eye(6)[:3], [[1], [-1]]))
    _, d = _slide_translations(state)
    alpha = _s_alphas(state, d)
    for key in ("-d", "xdot<0", "zdot<0", "+x", "+z", "-x", "-z", "x+z"):
        assert alpha[key] == 0.0, key
    assert alpha["d"] > 0 and alpha["d+y"] > 0
    # finger 1 and finger 3 lie in the x-z plane, so the grasp is symmetric under y -> -y
    assert alpha["+y"] > 0 and alpha["-y"] == pytest.approx(alpha["+y"], rel=1e-7)


def test_case1_humanlike_documented_behaviour() -> None:
    """Yaw + three pitches (digest): the same beta, but a 3-D TVMS and no pure translation at all."""
    state = _state("case1", "humanlike")
    contacts = ["f1_tip", "f3_link1", "f3_link2"]
    motion = _reachable(state, ["f3_link1", "f3_link2"], np.eye(6)[:, [0, 2, 4]])
    scaled = SCALE @ motion[:, 0]
    assert (
        np.degrees(np.arccos(min(1.0, abs(scaled @ BETA) / np.linalg.norm(scaled) / np.linalg.norm(BETA))))
        < 2
    )
    assert _reachable(state, contacts).shape[1] == 3
    assert _reachable(state, contacts, np.eye(6)[:, :3]).shape[1] == 0
    sliding = _state("case1-s", "humanlike")  # with the S-point: only the ray t d, t >= 0 (no y)
    free, d = _slide_translations(sliding)
    assert free.shape == (3, 0) and d[0] > 0 and d[2] > 0
    alpha = _s_alphas(sliding, d)
    assert alpha["d"] > 0
    assert alpha["+y"] == alpha["-y"] == alpha["d+y"] == alpha["-d"] == 0.0


def test_case2_initial_state_is_a_feasible_grasp_that_can_lift() -> None:
    """Case 2's initial state (L-points for fingers 2 and 4, base D-point) balances the weight
    and moves the object along every upward RVDS vertex of eq. 37 (all alphas positive)."""
    for variant in ("default", "humanlike"):
        state = _state("case2", variant)
        assert [c.type for c in state.contacts] == ["D", "F", "L", "F", "L"]
        result = tvmmp(state)
        assert result.feasible and set(result.status[0]) == {"optimal"}
        assert np.all(result.alpha > 0)


# -------------------------------------------------------- malformed scenarios (the generator's checks)
def _doc(**changes: Any) -> dict[str, Any]:
    doc = read_scenario("case1")
    for key, value in changes.items():
        doc[key] = value
    return doc


def test_unreachable_target_and_bad_poses() -> None:
    far = _doc()
    # the sphere's point farthest from finger 1's base, 0.3077 m away: beyond 2 links (and 3)
    far["contacts"][0]["paper"] = [0.425, 0.1, 0.3]
    with pytest.raises(
        ModelError, match=r"finger 1: point \[0\.1592.* out of reach \(0\.3077 m from the base\)"
    ):
        solve_variant(far, "default")  # the posture rule says so
    with pytest.raises(
        ModelError, match=r"IK target 'f1_tip': unreachable: residual 0\.\d+ m above the tolerance"
    ):
        solve_variant(far, "humanlike")  # no rule: the IK says so
    with pytest.raises(ModelError, match="geom 'palm': touches the object"):
        solve_variant(_doc(ignored_geoms=[]), "default")
    deep = _doc()
    deep["contacts"][0]["offset"] = -0.007  # tip centre 7 mm inside: 7.02 mm deep, contact 3.51 mm inside
    with pytest.raises(
        ModelError, match=r"geom 'f1_tip': contact 3\.51 mm from the paper's point \(> 3 mm\)"
    ):
        solve_variant(deep, "default")
    with pytest.raises(
        ModelError, match="geom 'f3_nail': named in the scenario's contact_types but not in the model"
    ):
        solve_variant(_doc(contact_types={"f1_tip": "F", "f3_nail": "F"}), "default")


def test_case2_finger3_in_plane_would_go_below_the_palm() -> None:
    """Without the out-of-plane start and the pitch0 >= 0 bound, finger 3's elbow dips 15 mm into the palm."""
    doc = read_scenario("case2")
    v = doc["variants"]["default"]
    v["start"].update({"f3_yaw0": 0.0, "f3_yaw1": 0.0, "f3_pitch0": -0.1})
    v["bounds"].pop("f3_pitch0")
    with pytest.raises(ModelError, match=r"geom 'f3_link1': goes below the palm \(z = -0\.015"):
        solve_variant(doc, "default")


# ------------------------------------------------------- Case 1: finger 1's posture by a rule
def test_case1_finger1_posture_is_the_rule() -> None:
    """Planar fingertip rule: yaw1 = 0, base, elbow and fingertip in one vertical plane, elbow up,
    the fingertip on the paper's point; the stored solution is the rule's posture, not an IK's choice."""
    doc = read_scenario("case1")
    sc = load_scenario("case1")
    m, d = sc.model, sc.data
    solution = doc["variants"]["default"]["solution"]
    assert (
        solution["posture"]["rule"] == "planar_fingertip"
        and "f1_yaw0" not in doc["variants"]["default"]["start"]
    )
    rule = rule_posture(m, doc, "default")
    for name, angle in rule.angles.items():
        assert solution["qpos"][name] == pytest.approx(angle, abs=1e-12)
    assert abs(solution["qpos"]["f1_yaw1"]) < 1e-12
    base, elbow = d.xpos[m.body("f1_link1").id], d.xpos[m.body("f1_link2").id]
    tip = d.geom_xpos[m.geom("f1_tip").id]
    np.testing.assert_allclose(elbow, solution["posture"]["elbow"], atol=1e-12)
    normal = np.cross(tip - base, [0.0, 0.0, 1.0])
    assert abs((elbow - base) @ normal) / np.linalg.norm(normal) < 1e-12  # one vertical plane
    assert elbow[2] > tip[2] > 0  # elbow up
    for p in (elbow - base, tip - elbow):
        assert np.linalg.norm(p) == pytest.approx(0.1, abs=1e-12)
    on_sphere = doc["variants"]["default"]["solution"]["contacts"]["f1_tip"]["on_sphere"]
    (f1,) = [c for c in sc.state().contacts if c.name == "f1_tip"]
    np.testing.assert_allclose(f1.position, on_sphere, atol=1e-9)  # touching exactly


def test_case1_finger3_contacts_on_the_printed_points() -> None:
    """The line-thin hand (capsules of 0.01 mm) puts finger 3's contacts on the paper's points (within 5 um)."""
    state = _state("case1")
    printed = {"f3_link1": [0.075, 0.0, 0.0], "f3_link2": [0.171, 0.0, 0.072]}
    for c in state.contacts:
        if c.name in printed:
            assert np.linalg.norm(c.position - printed[c.name]) <= 5.1e-6
    sc = load_scenario("case1")
    assert sc.model.geom("f3_link1").size[0] == 1e-5 and sc.model.geom("f1_tip").size[0] == 2e-5


def test_case1_tvmm_against_finger1_posture() -> None:
    """The shape docs/case1_tvmm_posture.png shows (scaled 4-D TVMM, 1/s^4): over the fingertip postures
    the rule's (psi = 0) is the largest, 1.651e6; a dip to ~3.5e5 near psi = -20 deg; contacts on link 2
    give 2.8e5 .. 8.7e5, branch B rising with the distance from the joint; the paper's 8.4e5 lies inside."""
    from mjtvm.polytopes.tvms import tvms

    rows = finger1_tvmm_curve(
        tip_angles=np.radians([-90.0, -60.0, -40.0, -20.0, -5.0, 0.0]), alongs=[0.045, 0.055, 0.0625]
    )
    tip = {round(float(np.degrees(r["parameter"]))): r["tvmm"] for r in rows if r["contact"] == "tip"}
    assert set(tip) == {-90, -60, -40, -20, -5, 0}
    assert all(r["dimension"] == 4 for r in rows)
    assert tip[0] == pytest.approx(tvms(_state("case1")).affine_volume, rel=1e-6)
    assert tip[0] == pytest.approx(1.6511e6, rel=1e-4) and tip[0] == max(tip.values())
    assert tip[-60] == pytest.approx(1.5912e6, rel=1e-3) and tip[-20] == pytest.approx(3.4565e5, rel=1e-3)
    assert tip[-60] > tip[-40] > tip[-20] < tip[-5] < tip[0]
    side = sorted(
        (r["along"], r["parameter"] % (2 * np.pi), r["tvmm"]) for r in rows if r["contact"] == "side"
    )
    b = [v for _, phi, v in side if phi > np.radians(315)]
    assert len(b) == 3 and b[0] < b[1] < b[2] and b[2] == pytest.approx(8.727e5, rel=1e-3)
    values = [r["tvmm"] for r in rows]
    assert min(values) < 8.4e5 < max(values)  # the paper's value is one of finger 1's feasible postures
