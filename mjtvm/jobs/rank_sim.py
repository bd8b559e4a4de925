r"""The simulated columns of ``mjtvm rank --verify``: one dataset grasp in MuJoCo.

[`sim_columns()`][mjtvm.jobs.rank_sim.sim_columns] asks the physics room for the grasp's
simulated model ([`dataset_sim_model()`][mjtvm.physics.grasp_sim.dataset_sim_model]) and its hold
and speed tests ([`grasp_sim()`][mjtvm.physics.grasp_sim.grasp_sim]); a grasp that cannot be
simulated (no motor data, a REFS other than the weight, a mesh object from ``obj_path``) or was
not evaluated gets empty columns and the reason in ``sim_failure``. The protocol, its constants
and the columns: ``docs/physics-check.md``, "Whole datasets".
"""

from __future__ import annotations

from typing import Any

from mjtvm.errors import MjtvmError
from mjtvm.jobs.rank_row import SIM_FIELDS
from mjtvm.model.state import GraspState

__all__ = ["not_simulated", "sim_columns"]


def not_simulated(why: str) -> dict[str, Any]:
    """Empty simulated columns, ``sim_failure`` saying why."""
    return {**dict.fromkeys(SIM_FIELDS), "sim_failure": " ".join(why.split())}


def sim_columns(
    grasp: Any, state: GraspState, result: Any, *, hold_time: float | None = None
) -> dict[str, Any]:
    """The ``sim_*`` columns of one evaluated grasp (module docstring).

    Parameters
    ----------
    grasp
        The dataset grasp ([`Grasp`][mjtvm.grasp.resolve.loaded.Grasp]).
    state, result
        Its grasp state and Problem 2 result, with witnesses.
    hold_time
        s each push of the hold test lasts (``None``: the protocol's 2 s).

    Returns
    -------
    dict
        [`SIM_FIELDS`][mjtvm.jobs.rank_row.SIM_FIELDS], in order.
    """
    from mjtvm.jobs.replay import grasp_defaults
    from mjtvm.physics.grasp_sim import dataset_sim_model, grasp_sim

    try:
        mu, mg = grasp_defaults(grasp, None, None)
        model = dataset_sim_model(grasp, state, mu=mu, mg=mg)
        out = grasp_sim(
            model,
            grasp.data.qpos.copy(),
            state,
            result,
            object_body=grasp.object_body,
            hold_duration=hold_time,
        )
    except MjtvmError as e:
        return not_simulated(f"not simulated: {e}")
    return {key: out[key] for key in SIM_FIELDS}
