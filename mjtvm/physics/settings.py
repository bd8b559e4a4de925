r"""The rollouts' settings and model: [`SimSettings`][mjtvm.physics.settings.SimSettings] and [`sim_model()`][mjtvm.physics.settings.sim_model].

Step 1 of the protocol in [`mjtvm.physics.simulate`][mjtvm.physics.simulate]: the simulation and pass/fail
settings of a rollout, and the copy of the lift's model a rollout runs on (friction cones,
contact softness, time step, the finger geoms' friction by contact type, the object's weight).
[`mjtvm.physics.simulate`][mjtvm.physics.simulate] re-exports both names.
"""

from __future__ import annotations

import copy
import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Literal

import mujoco
import numpy as np

from mjtvm.errors import ModelError, ParamError
from mjtvm.grasp.resolve.state import geom_id

__all__ = ["SimSettings", "sim_model", "with_integration"]

_INTEGRATORS = {
    "euler": mujoco.mjtIntegrator.mjINT_EULER,
    "implicitfast": mujoco.mjtIntegrator.mjINT_IMPLICITFAST,
    "implicit": mujoco.mjtIntegrator.mjINT_IMPLICIT,
    "rk4": mujoco.mjtIntegrator.mjINT_RK4,
}
"""``SimSettings.integrator`` -> MuJoCo's ``mjtIntegrator``."""


@dataclass(frozen=True)
class SimSettings:
    r"""Simulation and pass/fail settings ([`mjtvm.physics.simulate`][mjtvm.physics.simulate]; SI units, angles in degrees).

    ``edge_tol``: a rollout fails when an actuator runs more than this fraction faster than
    its operation range's largest speed (the speed edge: a box's speed limit, a motor's
    no-load speed after the joint's losses; ``Drive.speed_limits``).

    ``armature_scale`` scales the actuators' rotor inertia and ``inertial_ff`` adds the
    computed inertial and Coriolis torques of the tracked setpoints to the feedforward:
    both are ablations of the quasi-static assumption, off by default.

    ``integrator``: MuJoCo's integrator of the rollouts (``m.opt.integrator``), ``None`` keeping
    the model's own (``mjtvm verify``'s protocol: the hands' files leave MuJoCo's default,
    Euler). ``mjtvm rank --verify``'s hold test runs
    [`HOLD_SETTINGS`][mjtvm.physics.disturb.HOLD_SETTINGS] (implicitfast at 1 ms).

    ``servo`` (1/s): the position loop on the held configuration during the settle only
    ([`Servo`][mjtvm.physics.squeeze.Servo], speed setpoints ``servo (l_0 - l)``); 0, the
    default: setpoints 0 (a damper). Off during the startup and the window, so the loop
    produces no speed the rollout measures (``docs/physics-check.md``, "The squeeze hold").
    """

    timestep: float = 2.5e-4
    cone: Literal["elliptic", "pyramidal"] = "elliptic"
    solref: tuple[float, float] = (0.002, 1.0)
    solimp: tuple[float, float, float, float, float] = (0.9, 0.95, 0.001, 0.5, 2.0)
    impratio: float = 10.0
    settle: float = 0.03
    startup: float = 0.002
    window: float = 0.005
    track: bool = True
    inertial_ff: bool = False
    armature_scale: float = 1.0
    speed_tol: float = 0.10
    angle_tol: float = 10.0
    slip_tol: float = 0.05
    slip_floor: float = 1e-5
    lost_gap: float = 5e-4
    edge_tol: float = 0.01
    integrator: Literal["euler", "implicitfast", "implicit", "rk4"] | None = None
    servo: float = 0.0

    def __post_init__(self) -> None:
        for name in (
            "timestep",
            "settle",
            "startup",
            "window",
            "speed_tol",
            "angle_tol",
            "slip_tol",
            "slip_floor",
            "lost_gap",
            "edge_tol",
            "impratio",
            "armature_scale",
            "servo",
        ):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0) or (name in ("timestep", "window") and value == 0):
                raise ParamError(name, f"expected a finite number >= 0, got {value!r}", value)
        if self.cone not in ("elliptic", "pyramidal"):
            raise ParamError("cone", f"expected 'elliptic' or 'pyramidal', got {self.cone!r}", self.cone)
        if self.integrator is not None and self.integrator not in _INTEGRATORS:
            raise ParamError(
                "integrator",
                f"expected one of {', '.join(map(repr, _INTEGRATORS))} or None, got {self.integrator!r}",
                self.integrator,
            )

    def steps(self, seconds: float) -> int:
        return round(seconds / self.timestep)


def sim_model(
    model: mujoco.MjModel,
    contact_types: Mapping[str, str],
    *,
    mu: float,
    mg: float | None = None,
    object_body: str = "object",
    settings: SimSettings | None = None,
) -> mujoco.MjModel:
    r"""A copy of ``model`` set up for rollouts (step 1 of [`mjtvm.physics.simulate`][mjtvm.physics.simulate]).

    Parameters
    ----------
    model
        A model whose state joints each have one ``<dcmotor>`` with ``input="vel ff"``
        ([`attach_dcmotors()`][mjtvm.physics.attach.attach_dcmotors] gives any hand those).
    contact_types
        Geom label (`geom_label()`: its name, or ``"<body>/geom<n>"``
        when unnamed) -> ``"F"``, ``"L"``, ``"S"`` or ``"D"`` (a state's contacts). Geoms
        not listed: ``"D"`` on the world body, else ``"F"``.
    mu
        Coulomb coefficient of the F- and S-geoms (and of finger geoms not listed).
    mg
        Object weight (N); the object body's mass and inertia are scaled to it. Default: as is.

    Raises
    ------
    ModelError
        Unknown object body or a contact-type key that is no geom of the model.
    """
    st = settings or SimSettings()
    m = copy.deepcopy(model)
    m.opt.timestep = st.timestep
    if st.integrator is not None:
        m.opt.integrator = int(_INTEGRATORS[st.integrator])
    m.opt.cone = int(
        mujoco.mjtCone.mjCONE_ELLIPTIC if st.cone == "elliptic" else mujoco.mjtCone.mjCONE_PYRAMIDAL
    )
    m.opt.impratio = st.impratio
    m.actuator_armature[:] *= st.armature_scale
    ob = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, object_body)
    if ob < 0:
        raise ModelError(f"body {object_body!r}", "not in the model")
    if mg is not None:
        if not (math.isfinite(mg) and mg > 0):
            raise ParamError("mg", f"expected a positive weight (N), got {mg!r}", mg)
        g = float(np.linalg.norm(m.opt.gravity))  # the weight along the model's gravity, as the REFS
        if g == 0.0 or float(m.body_mass[ob]) == 0.0:
            raise ParamError(
                "mg",
                "the object has no weight to scale (the model's gravity or the object's mass is 0): "
                'give the model a gravity (<option gravity="0 0 -9.81"/>) and the object a mass',
            )
        scale = mg / (float(m.body_mass[ob]) * g)
        m.body_mass[ob] *= scale
        m.body_inertia[ob] *= scale
    kinds = {geom_id(m, label, "contact_types geom"): kind for label, kind in contact_types.items()}
    inside = {ob}
    for b in range(ob + 1, m.nbody):  # parents precede children: the object's subtree
        if int(m.body_parentid[b]) in inside:
            inside.add(b)
    for g in range(m.ngeom):
        m.geom_solref[g] = st.solref
        m.geom_solimp[g] = st.solimp
        if int(m.geom_bodyid[g]) in inside:
            continue
        kind = kinds.get(g, "D" if int(m.geom_bodyid[g]) == 0 else "F")
        m.geom_priority[g] = 1  # the finger's (palm's) parameters decide the contact
        m.geom_condim[g] = 3 if kind in ("F", "S") else 1
        m.geom_friction[g] = (mu, 0.005, 0.0001)
    return m


def with_integration(model: mujoco.MjModel, settings: SimSettings) -> mujoco.MjModel:
    """``model`` with the time step and integrator of ``settings`` (``integrator=None``: the
    model's own): ``model`` itself when it has them already, else a copy."""
    want = model.opt.integrator if settings.integrator is None else int(_INTEGRATORS[settings.integrator])
    if model.opt.timestep == settings.timestep and model.opt.integrator == want:
        return model
    m = copy.deepcopy(model)
    m.opt.timestep = settings.timestep
    m.opt.integrator = want
    return m
