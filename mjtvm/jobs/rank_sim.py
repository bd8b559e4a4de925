r"""The simulated columns of ``mjtvm rank --verify``: one dataset grasp in MuJoCo.

[`sim_columns()`][mjtvm.jobs.rank_sim.sim_columns] asks the physics room for the grasp's
simulated model ([`dataset_sim_model()`][mjtvm.physics.grasp_sim.dataset_sim_model]) and its hold
and speed tests ([`grasp_sim()`][mjtvm.physics.grasp_sim.grasp_sim]); a grasp that cannot be
simulated (no motor data, a REFS other than the weight, a hand on a free joint) or was not
evaluated gets empty columns and the reason in ``sim_failure``. With the grasp's batch and entry,
the motors are attached to the grasp's own model (its object file, scale and posed root:
[`BatchModels.spec()`][mjtvm.grasp.resolve.batch.BatchModels.spec]), compiled once per
(grasp file, object file, root, frame, and scale for a mesh object) in this process and kept for the
`MOTORIZED_CACHE_SIZE` most recently used. The protocol, its constants
and the columns: ``docs/physics-check.md``, "Whole datasets".
"""

from __future__ import annotations

from collections import OrderedDict
from typing import Any

from mjtvm.errors import MjtvmError
from mjtvm.jobs.rank_row import SIM_FIELDS
from mjtvm.model.state import GraspState

__all__ = ["MOTORIZED_CACHE_SIZE", "not_simulated", "sim_columns"]

MOTORIZED_CACHE_SIZE = 8
"""Motorized models kept per process (a dataset's grasps of one object come in runs)."""

_MOTORIZED: OrderedDict[tuple[Any, ...], Any] = OrderedDict()
"""(grasp file, object file, scale, posed root, centre-of-mass frame) -> the motorized model."""


def not_simulated(why: str) -> dict[str, Any]:
    """Empty simulated columns, ``sim_failure`` saying why."""
    return {**dict.fromkeys(SIM_FIELDS), "sim_failure": " ".join(why.split())}


def _motorized(grasp: Any, batch: Any, entry: Any) -> Any:
    """The grasp's motorized model, from the cache (compiled on a miss)."""
    from mjtvm.physics.grasp_sim import motorized_model, scale_free

    if batch is None or entry is None:
        return motorized_model(grasp)
    # A primitive object's scale is copied onto the model per grasp (dataset_sim_model): one
    # model serves every scale of it; a mesh's scale is compiled into its vertices.
    scale = None if entry.obj_path is None and scale_free(grasp) else float(entry.obj_scale)
    key = (batch.file, entry.obj_path, scale, entry.root is not None, bool(entry.com_frame))
    if key in _MOTORIZED:
        _MOTORIZED.move_to_end(key)
    else:
        _MOTORIZED[key] = motorized_model(grasp, batch.spec(entry))
        while len(_MOTORIZED) > MOTORIZED_CACHE_SIZE:
            _MOTORIZED.popitem(last=False)
    return _MOTORIZED[key]


def sim_columns(
    grasp: Any,
    state: GraspState,
    result: Any,
    *,
    hold_time: float | None = None,
    batch: Any = None,
    entry: Any = None,
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
    batch, entry
        The [`BatchModels`][mjtvm.grasp.resolve.batch.BatchModels] and the
        [`DatasetGrasp`][mjtvm.grasp.document.dataset.DatasetGrasp] the grasp was built from:
        the model its own object (``obj_path``); without them the grasp file's spec, whose
        object a dataset ``obj_path`` replaces (then ``sim_failure`` says so).

    Returns
    -------
    dict
        [`SIM_FIELDS`][mjtvm.jobs.rank_row.SIM_FIELDS], in order.
    """
    from mjtvm.jobs.replay import grasp_defaults
    from mjtvm.physics.grasp_sim import dataset_sim_model, grasp_sim

    try:
        mu, mg = grasp_defaults(grasp, None, None)
        model = dataset_sim_model(grasp, state, mu=mu, mg=mg, motorized=_motorized(grasp, batch, entry))
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
