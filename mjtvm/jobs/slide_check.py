r"""The slide-direction check of the S variant along the lift.

[`slide_check()`][mjtvm.jobs.slide_check.slide_check] settles the slide-direction ambiguity of the S variant: fingers 2 and 4,
frictional (mu), are driven with the paper's minimum-norm lift motion (their slip is then the
one that motion produces), or made to out-run the object (the slip of the literal reading),
or left frictionless (control); it reports the direction of MuJoCo's friction force
(``slide-check.csv`` of ``mjtvm verify --slide-check``).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import replace
from typing import Any

import numpy as np

from mjtvm.lift.states import lift_state
from mjtvm.lift.trajectory import Lift
from mjtvm.physics.check import contact_types, motor_model
from mjtvm.physics.simulate import SimSettings, rollout, sim_model
from mjtvm.physics.witness import witness_drive
from mjtvm.problem2.tvmmp import tvmmp

__all__ = ["slide_check"]


def slide_check(
    lift: Lift,
    indices: Sequence[int],
    *,
    speed: float = 0.2,
    mu: float = 0.3,
    mg: float = 1.0,
    settings: SimSettings | None = None,
) -> list[dict[str, Any]]:
    r"""Friction direction at fingers 2 and 4 while they slide during the lift .

    The object is lifted along +z at ``speed`` (m/s; at most half the LP's alpha along +z);
    fingers 1 and 3 stick (F, mu). Modes: ``physical`` (fingers 2 and 4 frictional, the
    paper's minimum-norm motion, so they slip as that motion makes them), ``literal``
    (frictional, driven to slip against that direction at the same slip speed: they out-run
    the object) and ``frictionless`` (L-points, control). Feedforward: the central solution
    ([`central_witness()`][mjtvm.physics.witness.central_witness]) of the mode's LP (S-points of that reading;
    L-points for the control) for the twist ``speed e_z``, or of the L-point LP where the
    reading's LP has none (``ff`` column). Per S geom: ``cos`` of MuJoCo's mean tangential
    friction force on the object and of the measured slip with the physical slide direction
    $\hat p$ (eq. 13), the friction force's z component (N) and the twist errors.
    """
    ez = np.array([[0.0, 0.0, 1.0, 0.0, 0.0, 0.0]])
    rows = []
    for i in indices:
        states = {
            m: lift_state(lift, i, variant=v, reading=r, mu=mu, mg=mg).with_(rvds=ez)  # type: ignore[arg-type]
            for m, v, r in (
                ("physical", "S", "physical"),
                ("literal", "S", "literal"),
                ("frictionless", "L", "physical"),
            )
        }
        hats = {
            c.name.split("#")[0]: np.asarray(c.slide_direction)
            for c in states["physical"].contacts
            if c.type == "S"
        }
        alpha_l = float(tvmmp(states["frictionless"], witnesses=False).alpha[0, 0])
        v = min(speed, 0.5 * alpha_l)
        slip = {g: float(np.linalg.norm(s)) * v for g, s in zip(lift.geoms, lift.slips[i]) if g in hats}
        for mode, state in states.items():
            res_lp = tvmmp(state, witnesses=False)
            ok = res_lp.status[0][0] == "optimal" and float(res_lp.alpha[0, 0]) >= v
            drive = witness_drive(state if ok else states["frictionless"], 0, 0, v, 1.0)
            kinds = {g: ("S" if mode == "literal" else "L") for g in hats}
            drive = replace(
                drive,
                contacts=tuple((g, kinds.get(g, k)) for g, k in drive.contacts),
                slips={
                    g: (slip[g] if mode == "literal" else 0.0, -h if mode == "literal" else h)
                    for g, h in hats.items()
                },
            )
            model = sim_model(
                motor_model(lift.scenario),
                contact_types(state),
                mu=mu,
                mg=mg,
                settings=settings,
                object_body=lift.scenario.object_body,
            )
            res = rollout(
                model, lift.qpos[i], drive, settings=settings, object_body=lift.scenario.object_body
            )
            for g, hat in hats.items():
                force, sl = res.friction[g]
                rows.append(
                    {
                        "state": i,
                        "z": float(lift.z[i]),
                        "mode": mode,
                        "ff": mode if ok else "L",
                        "geom": g,
                        "speed": v,
                        "slip_speed": slip[g],
                        "friction_cos_phys": _cos(force, hat),
                        "friction_z": float(force[2]),
                        "friction_t": float(np.linalg.norm(force)),
                        "slip_cos_phys": _cos(sl, hat),
                        "slip_measured": float(np.linalg.norm(sl)),
                        "speed_error": res.speed_error,
                        "angle_error": res.angle_error,
                        "passed": res.passed,
                        "reason": res.reason,
                    }
                )
    return rows


def _cos(a: np.ndarray, b: np.ndarray) -> float:
    na = float(np.linalg.norm(a))
    return float(a @ b) / na if na > 1e-9 else math.nan
