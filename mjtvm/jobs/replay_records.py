r"""The records of the lift replay and their files: Problem 2 at one state of the lift
([`Record`][mjtvm.jobs.replay_records.Record], [`solve_state()`][mjtvm.jobs.replay_records.solve_state]), the records as CSV and the lift as JSON.

[`mjtvm.jobs.replay`][mjtvm.jobs.replay] runs the replay and writes these files.
"""

from __future__ import annotations

import csv
import io
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from mjtvm.lift.states import READINGS, lift_state, slide_directions
from mjtvm.lift.trajectory import Lift
from mjtvm.model.state import GraspState
from mjtvm.problem2.tvmmp import TvmmpResult, tvmmp

__all__ = ["Record", "lift_dict", "record_state", "records_csv", "solve_state"]

_EDGE_TOL = 1e-6  # relative: an operating point this close to its range's edge is saturated


@dataclass(frozen=True, eq=False)
class Record:
    r"""Problem 2 at one state of the lift.

    Attributes
    ----------
    variant, reading
        Type of the L/S contacts (``"L"`` or ``"S"``) and the slide-direction reading
        (``None`` for L-points, where it plays no part).
    mu, mg
        Friction coefficient and object weight (N).
    index, z, s
        State index, object origin height (m) and travel along the lift (m; the lift's path
        parameter, `s`).
    result
        The [`TvmmpResult`][mjtvm.problem2.tvmmp.TvmmpResult] (alpha_kl, status, TVMMP, limiting pair, timings).
    solver
        The backend that produced ``result``.
    saturated
        Joints whose (torque, speed) in the limiting pair's witness lies on the edge of their
        operation range (one optimal vertex; other optima may differ).
    state
        The [`GraspState`][mjtvm.model.state.GraspState] that was solved (kept for the recording).
    """

    variant: str
    reading: str | None
    mu: float
    mg: float
    index: int
    z: float
    s: float
    result: TvmmpResult
    solver: str
    saturated: tuple[str, ...]
    state: GraspState = field(repr=False, compare=False)

    def row(self) -> dict[str, Any]:
        """The CSV row (``scenario`` and ``hand`` are added by the writer)."""
        r = self.result
        out: dict[str, Any] = {
            "variant": self.variant,
            "reading": self.reading or "",
            "mu": self.mu,
            "mg": self.mg,
            "state": self.index,
            "z": self.z,
            "s": self.s,
            "tvmmp": "" if r.tvmmp is None else r.tvmmp,
            "feasible": r.feasible,
        }
        for k, l in np.ndindex(*r.alpha.shape):
            ok = r.status[k][l] == "optimal"
            out[f"alpha_k{k}_l{l}"] = float(r.alpha[k, l]) if ok else ""
            out[f"status_k{k}_l{l}"] = r.status[k][l]
        out["limiting_k"], out["limiting_l"] = ("", "") if r.limiting is None else r.limiting
        out["certified"] = not r.uncertified()
        t = r.timings
        out.update(
            saturated=";".join(self.saturated),
            solver=self.solver,
            assemble_s=t.assemble_s,
            solve_s=t.solve_s,
            total_s=t.total_s,
            num_lps=t.num_lps,
        )
        return out

    def to_dict(self) -> dict[str, Any]:
        """JSON form: the row's identity plus the ``mjtvm.result/1`` document (no witnesses)."""
        return {
            "variant": self.variant,
            "reading": self.reading,
            "mu": self.mu,
            "mg": self.mg,
            "state": self.index,
            "z": self.z,
            "s": self.s,
            "solver": self.solver,
            "saturated": list(self.saturated),
            **self.result.to_dict(witnesses=False),
        }


def _saturated(state: GraspState, result: TvmmpResult) -> tuple[str, ...]:
    if result.limiting is None:
        return ()
    w = result.witnesses[result.limiting[0]][result.limiting[1]]
    if w is None:
        return ()
    out = []
    for name, rng, tau, qd in zip(  # joints, or the actuators of a transmission
        state.actuator_names, state.operation_ranges, w.torques, w.range_speeds, strict=True
    ):
        if rng.max_speed_at(float(tau)) - abs(float(qd)) <= _EDGE_TOL * rng.max_speed:
            out.append(name)
    return tuple(out)


def solve_state(state: GraspState) -> tuple[TvmmpResult, str]:
    """Problem 2 with the default backend; returns the result and the backends that settled it.

    A [`SolverError`][mjtvm.errors.SolverError] (neither solver settles a pair) propagates: solver
    trouble is reported, not hidden.
    """
    result = tvmmp(state)
    used = sorted({b for row in result.settled_by for b in row if b is not None}) or ["highs"]
    return result, "+".join(used)


def record_state(
    lift: Lift, i: int, base: GraspState, variant: str, reading: str | None, mu: float, mg: float
) -> Record:
    """The [`Record`][mjtvm.jobs.replay_records.Record] of lift state ``i`` under given contact conditions.

    Parameters
    ----------
    lift, i
        The lift and the state's index.
    base
        The state's grasp (``lift_state``'s ``base``), shared by every condition.
    variant, reading
        Type of the L/S contacts and the slide-direction reading (``None`` for L-points).
    mu, mg
        Friction coefficient and object weight (N).

    Returns
    -------
    Record
        Problem 2 at the state ([`solve_state()`][mjtvm.jobs.replay_records.solve_state]).
    """
    state = lift_state(lift, i, variant=variant, reading=reading or "physical", mu=mu, mg=mg, base=base)  # type: ignore[arg-type]
    result, solver = solve_state(state)
    return Record(
        variant,
        reading,
        mu,
        mg,
        i,
        float(lift.z[i]),
        float(lift.s[i]),
        result,
        solver,
        _saturated(state, result),
        state,
    )


def _columns(records: Sequence[Record]) -> list[str]:
    return list(records[0].row()) if records else []


def records_csv(records: Sequence[Record], meta: dict[str, Any], sweeps: Sequence[str] | None = None) -> str:
    """The records as CSV text (``lift.csv``, ``lift-sweeps.csv``).

    Parameters
    ----------
    records
        The records, one line each ([`Record.row()`][mjtvm.jobs.replay_records.Record.row]).
    meta
        ``scenario`` and ``hand``, the first columns of every line.
    sweeps
        One name per record: adds the ``sweep`` column that tells the Fig. 9 curves apart (the
        (mu 0.3, mg 2) curve belongs to both sweeps).

    Returns
    -------
    str
        The CSV text.
    """
    extra = ["sweep"] if sweeps is not None else []
    buf = io.StringIO(newline="")
    writer = csv.DictWriter(buf, fieldnames=[*extra, "scenario", "hand", *_columns(records)])
    writer.writeheader()
    for k, rec in enumerate(records):
        tag = {"sweep": sweeps[k]} if sweeps is not None else {}
        writer.writerow({**tag, "scenario": meta["scenario"], "hand": meta["hand"], **rec.row()})
    return buf.getvalue()


def lift_dict(lift: Lift) -> dict[str, Any]:
    """The lift as JSON (``lift.json``'s ``lift``): its states, contacts and slide directions.

    Parameters
    ----------
    lift
        The scripted lift.

    Returns
    -------
    dict
        JSON-ready lists (``z``, ``qpos``, ``drift``, ..., ``slide_directions`` per reading).
    """
    slides = {
        reading: [
            {g: s.tolist() for g, s in slide_directions(lift, i, reading=reading).items()}  # type: ignore[arg-type]
            for i in range(lift.num_states)
        ]
        for reading in READINGS
    }
    return {
        "num_states": lift.num_states,
        "z": lift.z.tolist(),
        "limit": lift.limit,
        "max_step": lift.max_step,
        "tolerance": lift.tolerance,
        "marched_steps": lift.marched,
        "joints": list(lift.joints),
        "geoms": list(lift.geoms),
        "roles": list(lift.roles),
        "drift": lift.drift.tolist(),
        "residual": lift.residual.tolist(),
        "base": list(lift.base),
        "base_contact": lift.base_contact.tolist(),
        "touching": [list(t) for t in lift.touching],
        "contact_points": lift.points.tolist(),
        "qpos": lift.qpos.tolist(),
        "slide_directions": slides,
    }
