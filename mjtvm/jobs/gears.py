r"""Gear-ratio sweep: the quasi-static TVMMP and the dynamic one against the gear ratio.

The same motor behind an ideal gear of ratio N gives the joint N times its torque, 1/N of
its speed and N^2 times its rotor inertia. [`gear_sweep()`][mjtvm.jobs.gears.gear_sweep] rescales the lift states'
operation ranges from the model's gear $N_0$ (torque x $N/N_0$, speed x
$N_0/N$: [`scaled()`][mjtvm.model.operation_range.OperationRange.scaled], exact for the
datasheet's range of an ideal gear) and sets every ``<dcmotor>``'s gear to N (MuJoCo reflects
the rotor inertia as armature x gear^2), then solves the TVMMP (eq. 32) and the dynamic TVMMP
(the minimum over l of [`dynamic_pair()`][mjtvm.physics.dynamic.dynamic_pair]) at the chosen states.

The quasi-static measure sees only torque against speed: once the grasp's torques fit,
a lower ratio is faster and its TVMMP keeps rising as N falls until the torque runs out. The
reflected inertia (x N^2) and the torque left for it (x N) move the dynamic optimum to a ratio
where the two balance.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from mjtvm.errors import ParamError
from mjtvm.jobs.verify import cached_lift
from mjtvm.lift.states import lift_state
from mjtvm.model.limits import with_limit_horizon
from mjtvm.physics.check import contact_types, motor_model
from mjtvm.physics.dynamic import dynamic_pair
from mjtvm.physics.simulate import sim_model
from mjtvm.problem2.tvmmp import tvmmp

__all__ = ["GEARS", "gear_sweep", "plot_gears"]

GEARS = (10.0, 15.0, 20.0, 25.0, 30.0, 40.0, 50.0, 60.0, 80.0, 100.0)
"""Default gear ratios of the sweep."""


def gear_sweep(
    grasp: str = "case2",
    ratios: Sequence[float] = GEARS,
    *,
    num_states: int = 30,
    states: Sequence[int] = (0, 5, 10, 15, 20, 25),
    variant: str = "L",
    mu: float = 0.3,
    mg: float = 1.0,
    limit_horizon: float | None = None,
) -> list[dict[str, Any]]:
    r"""Rows (ratio, state, TVMMP, dynamic TVMMP, limiting joint and term) of the sweep (module docstring).

    Parameters
    ----------
    grasp
        A shipped grasp (``case2``: the paper's lift) whose state joints have ``<dcmotor>`` s.
    ratios
        Gear ratios (motor turns per joint turn).
    states
        Lift state indices (of ``num_states``).
    limit_horizon
        Problem 2's travel horizon of the joint limits (m); ``None``: the grasp file's.
    """
    if not ratios or any(not (math.isfinite(r) and r > 0) for r in ratios):
        raise ParamError("ratios", f"expected positive gear ratios, got {list(ratios)!r}", list(ratios))
    lift = cached_lift(grasp, num_states)
    if getattr(lift.scenario, "transmission", None) is not None:
        raise ParamError("gears", "not available for a hand with a transmission (it rescales joint motors)")
    ob = lift.scenario.object_body
    base = motor_model(lift.scenario)
    rows = []
    for i in states:
        state0 = with_limit_horizon(lift_state(lift, i, variant=variant, mu=mu, mg=mg), limit_horizon)  # type: ignore[arg-type]
        model = sim_model(base, contact_types(state0), mu=mu, mg=mg, object_body=ob)
        acts = [a for a in range(model.nactuator) if model.actuator_gear[a, 0] > 0]
        gear0 = float(np.median(model.actuator_gear[acts, 0]))
        for n in ratios:
            f = n / gear0
            state = state0.with_(
                operation_ranges=tuple(r.scaled(torque=f, speed=1 / f) for r in state0.operation_ranges)
            )
            model.actuator_gear[acts, 0] = n
            res = tvmmp(state)
            row: dict[str, Any] = {"ratio": n, "state": i, "z": float(lift.z[i]), "tvmmp": res.tvmmp}
            best: tuple[float, int, str, str] | None = None
            if res.tvmmp is not None:
                for l in range(len(state.rvds if state.rvds is not None else [])):
                    if res.status[0][l] != "optimal":
                        continue
                    dyn = dynamic_pair(model, lift.qpos[i], state, 0, l, result=res, object_body=ob)
                    joint = state.joint_names[dyn.joint] if dyn.joint is not None else ""
                    if best is None or dyn.alpha < best[0]:
                        best = (dyn.alpha, l, joint, dyn.term)
            if best is not None:
                row.update(tvmmp_dyn=best[0], l_dyn=best[1], joint_dyn=best[2], term_dyn=best[3])
            rows.append(row)
        model.actuator_gear[acts, 0] = gear0
    return rows


def plot_gears(rows: Sequence[dict[str, Any]], title: str = "") -> bytes:
    """PNG: TVMMP and dynamic TVMMP against the gear ratio (log scale when the ratios span more
    than a decade), per state (thin) and their mean (thick, its maximum named in the key); the
    ratios with infeasible states counted in a note below the axes, never drawn at 0."""
    from mjtvm.jobs.figures import ALPHA_UNIT
    from mjtvm.jobs.style import figure, finish, no_value, png

    fig, ax = figure(6.5, 4.6)
    ratios = sorted({r["ratio"] for r in rows})
    for key, style, label in (("tvmmp", "-", "TVMMP (quasi-static)"), ("tvmmp_dyn", "--", "dynamic TVMMP")):
        per = {
            s: [next((r.get(key) for r in rows if r["state"] == s and r["ratio"] == n), None) for n in ratios]
            for s in dict.fromkeys(r["state"] for r in rows)
        }
        mean = np.array(
            [
                np.mean([v[k] for v in per.values() if v[k] is not None] or [np.nan])
                for k in range(len(ratios))
            ]
        )
        best = f", max at {ratios[int(np.nanargmax(mean))]:g}:1" if np.isfinite(mean).any() else ""
        (line,) = ax.plot(
            ratios, mean, style, lw=2.2, marker="o", ms=4, label=f"{label}, mean of the feasible states{best}"
        )
        for vals in per.values():
            ax.plot(
                ratios,
                [np.nan if v is None else v for v in vals],
                style,
                lw=0.6,
                alpha=0.4,
                color=line.get_color(),
            )
        if key == "tvmmp":
            no_value(ax, [n for n, m in zip(ratios, mean, strict=True) if np.isnan(m)], color="0.3",
                     label="no feasible state")  # fmt: skip
    infeasible = []
    for n in ratios:
        total = sum(1 for r in rows if r["ratio"] == n)
        bad = sum(1 for r in rows if r["ratio"] == n and r.get("tvmmp") is None)
        if bad:
            infeasible.append(f"{n:g}:1 {bad}/{total}")
    notes = [f"infeasible states: {', '.join(infeasible)}"] if infeasible else []
    if ratios and max(ratios) > 10.0 * min(ratios):
        ax.set_xscale("log")
        ax.set_xticks(ratios, [f"{n:g}" for n in ratios])
        ax.minorticks_off()
    ax.set_ylim(bottom=0.0)
    finish(
        fig,
        ax,
        xlabel="gear ratio N (motor turns per joint turn)",
        ylabel=rf"TVMMP $\alpha$ {ALPHA_UNIT}",
        title=title or "Gear-ratio sweep",
        notes=["thin lines: each lift state", *notes],
    )
    return png(fig)  # type: ignore[no-any-return]
