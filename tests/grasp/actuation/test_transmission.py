"""The transmission read from MuJoCo (mjtvm.grasp.actuation.transmission) against finite differences
and hand-derived values: actuator speeds against MuJoCo's actuator lengths, constraint rows
against the constrained points' and joints' positions, the 2F-85's four-bar velocity ratio
against the one derived from its pivots, and the independent hands' path unchanged."""

from __future__ import annotations

import tomllib
from pathlib import Path

import mujoco
import numpy as np
import pytest

from mjtvm.errors import ModelError
from mjtvm.grasp.actuation.transmission import is_independent, model_transmission

MODELS = Path(__file__).resolve().parents[3] / "models"
SHADOW = MODELS / "shadow_hand" / "shadow_right_3f.xml"
F85 = MODELS / "robotiq_2f85" / "robotiq_2f85.xml"
F85_GRASP = MODELS / "robotiq_2f85" / "robotiq_2f85-sphere.toml"
H = 1e-6


def _joint_ids(model: mujoco.MjModel, names: list[str] | None = None) -> list[int]:
    if names is None:
        return [j for j in range(model.njnt) if int(model.jnt_type[j]) == int(mujoco.mjtJoint.mjJNT_HINGE)]
    return [int(model.joint(n).id) for n in names]


def _f85() -> tuple[mujoco.MjModel, mujoco.MjData, list[int]]:
    """The 2F-85 at its grasp file's configuration (the linkage closed to machine precision)."""
    model = mujoco.MjModel.from_xml_path(str(F85))
    data = mujoco.MjData(model)
    doc = tomllib.loads(F85_GRASP.read_text(encoding="utf-8"))
    for name, value in doc["configuration"]["qpos"].items():
        data.qpos[model.joint(name).qposadr[0]] = value
    mujoco.mj_forward(model, data)
    return model, data, _joint_ids(model, doc["joints"])


def _shadow(seed: int = 0) -> tuple[mujoco.MjModel, mujoco.MjData, list[int]]:
    model = mujoco.MjModel.from_xml_path(str(SHADOW))
    data = mujoco.MjData(model)
    rng = np.random.default_rng(seed)
    lo, hi = model.jnt_range[:, 0], model.jnt_range[:, 1]
    data.qpos[:] = lo + (hi - lo) * rng.uniform(0.1, 0.9, model.nq)
    mujoco.mj_forward(model, data)
    return model, data, _joint_ids(model)


def _moved(
    model: mujoco.MjModel, data: mujoco.MjData, dofs: list[int], qd: np.ndarray, h: float
) -> mujoco.MjData:
    out = mujoco.MjData(model)
    out.qpos[:] = data.qpos
    out.qpos[[model.jnt_qposadr[model.dof_jntid[d]] for d in dofs]] += h * qd
    mujoco.mj_forward(model, out)
    return out


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_shadow_actuator_speeds_are_the_derivative_of_actuator_lengths(seed: int) -> None:
    """s = moment @ qd equals d(actuator_length)/dt (central differences, MuJoCo's own lengths:
    tendon J2 + J1 for rh_A_FFJ0), for a random posture and joint velocity."""
    model, data, joints = _shadow(seed)
    t = model_transmission(model, data, joints)
    assert len(t.actuator_names) == model.nactuator == 11
    assert t.constraint_jacobian.shape == (0, 13)
    dofs = [int(model.jnt_dofadr[j]) for j in joints]
    qd = np.random.default_rng(seed + 10).normal(size=len(dofs))
    plus, minus = _moved(model, data, dofs, qd, H), _moved(model, data, dofs, qd, -H)
    ids = list(t.actuator_ids)
    fd = (plus.actuator_length[ids] - minus.actuator_length[ids]) / (2 * H)
    np.testing.assert_allclose(t.moment @ qd, fd, atol=1e-8)
    ff = t.actuator_names.index("rh_A_FFJ0")
    row = dict(zip(t.joint_names, t.moment[ff], strict=True))
    assert row["rh_FFJ2"] == 1.0 and row["rh_FFJ1"] == 1.0  # the tendon's coefficients
    assert sum(abs(v) for v in row.values()) == 2.0
    np.testing.assert_array_equal(t.joint_damping, np.full(13, 0.05))  # class right_hand
    assert not is_independent(model, t, joints)


def test_f85_moment_and_driver_coupling() -> None:
    """One actuator on the tendon split = (right + left driver) / 2; the joint equality's row is
    e_right - 1 * e_left (polycoef 0 1 0 0 0); the connects' rows in the linkage plane only."""
    model, data, joints = _f85()
    t = model_transmission(model, data, joints)
    assert t.actuator_names == ("fingers_actuator",)
    expected = np.zeros(8)
    expected[[0, 4]] = 0.5
    np.testing.assert_array_equal(t.moment[0], expected)
    assert t.constraint_names == (
        "right_linkage/y",
        "right_linkage/z",
        "left_linkage/y",
        "left_linkage/z",
        "drivers",
    )  # x rows vanish: every joint turns about x, the linkages move in the y-z plane
    drivers = np.zeros(8)
    drivers[0], drivers[4] = 1.0, -1.0
    np.testing.assert_array_equal(t.constraint_jacobian[4], drivers)
    np.testing.assert_allclose(t.joint_damping, [0.1, 0, 0.00125, 0, 0.1, 0, 0.00125, 0])


def test_f85_connect_rows_are_the_derivative_of_the_anchor_gap() -> None:
    """Each connect row times qd is the rate of the gap between the anchor on the follower and
    its partner point on the coupler (positions from xpos/xmat, central differences)."""
    model, data, joints = _f85()
    t = model_transmission(model, data, joints)
    dofs = [int(model.jnt_dofadr[j]) for j in joints]

    def gaps(d: mujoco.MjData) -> np.ndarray:
        out = []
        for side in ("right", "left"):
            e = int(model.equality(f"{side}_linkage").id)
            b1, b2 = int(model.eq_obj1id[e]), int(model.eq_obj2id[e])
            p1 = d.xpos[b1] + d.xmat[b1].reshape(3, 3) @ model.eq_data[e, 0:3]
            p2 = d.xpos[b2] + d.xmat[b2].reshape(3, 3) @ model.eq_data[e, 3:6]
            out += list((p1 - p2)[1:])
        return np.array(out)

    np.testing.assert_allclose(gaps(data), 0.0, atol=1e-15)  # the configuration closes the linkage
    rng = np.random.default_rng(3)
    for _ in range(3):
        qd = rng.normal(size=8)
        fd = (gaps(_moved(model, data, dofs, qd, H)) - gaps(_moved(model, data, dofs, qd, -H))) / (2 * H)
        np.testing.assert_allclose(t.constraint_jacobian[:4] @ qd, fd, atol=1e-8)


def test_f85_four_bar_velocity_ratio() -> None:
    """With the coupler locked to the driver (qd = 0), each side is a four-bar: ground A-B
    (the driver's and the spring link's pivots), crank A-C (C the connect's anchor), coupler
    link C-D (D the follower's pivot) and rocker B-D. Rigid C-D gives
    (v_D - v_C) . (D - C) = 0 with v = w x r about the axis x: the spring link's rate per unit
    driver rate is [x (C - A)] . (D - C) / [x (D - B)] . (D - C). The constraint rows' null
    space with the coupler locked must give the same ratio."""
    model, data, joints = _f85()
    t = model_transmission(model, data, joints)
    x = np.array([1.0, 0.0, 0.0])
    for side, (drv, spr, fol) in (("right", (0, 2, 3)), ("left", (4, 6, 7))):
        j = {k: int(model.joint(f"{side}_{k}_joint").id) for k in ("driver", "spring_link", "follower")}
        a, b, dpt = (np.array(data.xanchor[j[k]]) for k in ("driver", "spring_link", "follower"))
        c = np.array(data.xpos[model.body(f"{side}_follower").id])  # the anchor: the follower's origin
        ratio = np.dot(np.cross(x, c - a), dpt - c) / np.dot(np.cross(x, dpt - b), dpt - c)
        rows = t.constraint_jacobian[[0, 1] if side == "right" else [2, 3]]
        # qd = (driver 1, coupler 0, spring link r, follower f): solve for r and f.
        r, _ = np.linalg.solve(rows[:, [spr, fol]], -rows[:, drv])
        assert r == pytest.approx(ratio, rel=1e-12)
        assert 0.9 < ratio < 1.1  # close to a parallelogram: the rocker follows the crank


def test_a_constraint_through_a_joint_outside_the_state_is_named() -> None:
    """Leaving a linkage joint out of the state would hold it still: refused, naming the
    constraint and the joint to add."""
    model, data, joints = _f85()
    without = [j for j in joints if model.joint(j).name != "right_coupler_joint"]
    with pytest.raises(
        ModelError,
        match=r"^equality 'right_linkage': constrains state joints together with 'right_coupler_joint'",
    ):
        model_transmission(model, data, without)
    only_right = [j for j in joints if model.joint(j).name.startswith("right")]
    with pytest.raises(
        ModelError, match=r"^actuator 'fingers_actuator': drives state joints and also 'left_driver_joint'"
    ):
        model_transmission(model, data, only_right)


@pytest.mark.parametrize(("folder", "xml"), [("allegro", "allegro_right.xml"), ("gripper3", "gripper3.xml")])
def test_independent_hands_keep_the_paper_path(folder: str, xml: str) -> None:
    """Joint actuators on distinct joints and no equality: the paper's independent joints."""
    model = mujoco.MjModel.from_xml_path(str(MODELS / folder / xml))
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    joints = [j for j in range(model.njnt) if int(model.jnt_type[j]) == int(mujoco.mjtJoint.mjJNT_HINGE)]
    t = model_transmission(model, data, joints)
    assert is_independent(model, t, joints)
    assert t.constraint_names == ()


def test_fixed_tendon_moment_arms_and_weld_rows() -> None:
    """A fixed tendon with coefficients r1 = 0.3, r2 = 0.7 under a motor of gear 2 has the
    moment row (0.6, 1.4) exactly; a weld of the second link to the world gives rows named
    /x ... /rz, those zero over the two hinges dropped: both hinges turn about y and the links
    stand along z, so only the translation along x and the rotation about y remain."""
    model = mujoco.MjModel.from_xml_string(
        """<mujoco><worldbody><body name="l1"><joint name="a" axis="0 1 0"/><geom size=".05" mass="1"/>
        <body name="l2" pos="0 0 .2"><joint name="b" axis="0 1 0"/><geom size=".05" mass="1"/></body>
        </body></worldbody>
        <tendon><fixed name="t"><joint joint="a" coef="0.3"/><joint joint="b" coef="0.7"/></fixed></tendon>
        <equality><weld name="w" body1="l2"/></equality>
        <actuator><motor name="m" tendon="t" gear="2"/></actuator></mujoco>"""
    )
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    t = model_transmission(model, data, [0, 1])
    np.testing.assert_allclose(t.moment, [[0.6, 1.4]], rtol=1e-15)
    assert t.constraint_names == ("w/x", "w/ry")
    np.testing.assert_allclose(t.constraint_residual, 0.0, atol=1e-15)
    assert not is_independent(model, t, [0, 1])


def test_round_off_of_a_shared_ancestor_does_not_couple_it() -> None:
    """A wrist hinge on the 2F-85's base: its columns of the linkage's connect rows are the
    ~1e-17 cross products of its axis and a zero lever arm, round-off that once pulled the
    whole linkage into a state of the wrist alone ("constrains state joints together with")."""
    import tomllib
    from pathlib import Path

    import mujoco

    from mjtvm.grasp.actuation.transmission import model_transmission

    root = Path(__file__).resolve().parents[3] / "models" / "robotiq_2f85"
    spec = mujoco.MjSpec.from_file(str(root / "robotiq_2f85.xml"))
    spec.body("base").add_joint(name="wrist", type=mujoco.mjtJoint.mjJNT_HINGE, axis=[0.0, 0.0, 1.0])
    model = spec.compile()
    data = mujoco.MjData(model)
    doc = tomllib.loads((root / "robotiq_2f85-sphere.toml").read_text(encoding="utf-8"))
    for name, value in doc["configuration"]["qpos"].items():
        data.qpos[model.jnt_qposadr[model.joint(name).id]] = value
    data.qpos[model.jnt_qposadr[model.joint("wrist").id]] = 0.3
    mujoco.mj_forward(model, data)
    found = model_transmission(model, data, [model.joint("wrist").id])
    assert found.constraint_names == ()


def _rows_one_by_one(
    model: mujoco.MjModel, data: mujoco.MjData, dofs: list[int]
) -> tuple[list[str], np.ndarray, np.ndarray]:
    """The equality rows on ``dofs``, read one efc row at a time (the reference the vectorised
    `equality_rows()` must equal entry for entry)."""
    from mjtvm.grasp.actuation.transmission import dense_efc_jacobian
    from mjtvm.grasp.contacts.touch import without_round_off

    efc = dense_efc_jacobian(model, data)
    names, rows, residuals, seen = [], [], [], {}
    for r in range(int(data.nefc)):
        if int(data.efc_type[r]) != int(mujoco.mjtConstraint.mjCNSTR_EQUALITY):
            continue
        e = int(data.efc_id[r])
        k = seen[e] = seen.get(e, -1) + 1
        row = without_round_off(efc[r])
        if not np.any(row[dofs] != 0.0):
            continue
        axes = {
            int(mujoco.mjtEq.mjEQ_CONNECT): "xyz",
            int(mujoco.mjtEq.mjEQ_WELD): ["x", "y", "z", "rx", "ry", "rz"],
        }
        label = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_EQUALITY, e) or f"equality#{e}"
        kind = axes.get(int(model.eq_type[e]))
        names.append(f"{label}/{kind[k]}" if kind else label)
        rows.append(without_round_off(row[dofs]))
        residuals.append(float(data.efc_pos[r]))
    return names, np.array(rows).reshape(len(rows), len(dofs)), np.array(residuals)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_equality_rows_and_moments_equal_a_row_by_row_reading(seed: int) -> None:
    """The 2F-85's connect rows (x, y, z of each) and the five-finger Shadow hand's joint
    couplings and sum tendons at random configurations: `model_transmission()` gives, bit for
    bit, what reading MuJoCo one row at a time gives."""
    from mjtvm.grasp.actuation.transmission import dense_moment
    from mjtvm.grasp.contacts.touch import without_round_off

    rng = np.random.default_rng(seed)
    f85, f85_data, f85_ids = _f85()
    shadow = mujoco.MjModel.from_xml_path(str(MODELS / "shadow_hand" / "shadow_right_coupled.xml"))
    shadow_data = mujoco.MjData(shadow)
    shadow_data.qpos[:] = rng.uniform(shadow.jnt_range[:, 0], shadow.jnt_range[:, 1])
    mujoco.mj_forward(shadow, shadow_data)
    for model, data, ids in ((f85, f85_data, f85_ids), (shadow, shadow_data, _joint_ids(shadow))):
        dofs = [int(model.jnt_dofadr[j]) for j in ids]
        t = model_transmission(model, data, ids)
        names, rows, residuals = _rows_one_by_one(model, data, dofs)
        assert t.constraint_names == tuple(names) and len(names) > 0
        np.testing.assert_array_equal(t.constraint_jacobian, rows)
        np.testing.assert_array_equal(t.constraint_residual, residuals)
        dense = np.array([without_round_off(row) for row in dense_moment(model, data)])
        driving = [a for a in range(model.nactuator) if np.any(dense[a, dofs] != 0.0)]
        assert t.actuator_ids == tuple(driving)
        np.testing.assert_array_equal(t.moment, [without_round_off(dense[a, dofs]) for a in driving])
