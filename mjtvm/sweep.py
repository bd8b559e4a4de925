r"""Parameter sweeps of Problem 2 over lifts: a grid, a local process pool or a Dask cluster.

A sweep is a list of :class:`SweepPoint` (scenario, hand, contact variant, slide reading,
mu, mg, lift state). Points that share a lift configuration are solved together by one
task, which builds the scripted lift once per worker process (the lift depends only on the
scenario, the hand and the number of states: mu and mg change the statics, not the motion),
reads each state's MuJoCo grasp once per worker, and solves each requested state with
:func:`~mjtvm.tvmmp.tvmmp`. The same tasks run

* serially (``jobs=1``),
* on a local process pool (``jobs > 1``, the ``forkserver`` start method: MuJoCo and
  HiGHS hold native state that should not be forked), or
* on a Dask cluster (``cluster="tcp://host:8786"`` or a ``distributed.Client``), the
  optional ``cluster`` extra. Dask was chosen over Ray because it installs as pure-Python
  wheels from PyPI, its ``LocalCluster`` runs the same code in tests, and ``Client(address)``
  attaches to any existing scheduler (including batch-queue clusters via dask-jobqueue).

Every way returns the same rows in the order of the points (tested).
"""

from __future__ import annotations

import itertools
import multiprocessing
from collections.abc import Iterable, Sequence
from concurrent.futures import ProcessPoolExecutor
from dataclasses import asdict, dataclass
from functools import lru_cache
from typing import Any

import numpy as np
from tqdm import tqdm

from .errors import StateError
from .state import GraspState
from .trajectory import READINGS, VARIANTS, Lift, lift_state, scripted_lift
from .tvmmp import tvmmp

__all__ = ["SweepPoint", "grid", "run_sweep"]


@dataclass(frozen=True)
class SweepPoint:
    """One Problem 2 evaluation: a lift state under given contact conditions.

    Parameters
    ----------
    scenario, hand
        Scenario name (``case2``) and hand variant (``default`` or ``humanlike``).
    variant
        Contact type of fingers 2 and 4: ``"L"`` or ``"S"``.
    reading
        Slide-direction reading of S-points: ``"physical"`` or ``"literal"``.
    mu, mg
        Friction coefficient and object weight (N).
    state
        Index of the lift state (0 = the initial grasp).
    num_states
        Number of states of the lift the index refers to.
    """

    scenario: str = "case2"
    hand: str = "default"
    variant: str = "L"
    reading: str = "physical"
    mu: float = 0.3
    mg: float = 1.0
    state: int = 0
    num_states: int = 30

    def __post_init__(self) -> None:
        if self.variant not in VARIANTS:
            raise StateError("variant", f"expected one of {VARIANTS}, got {self.variant!r}")
        if self.reading not in READINGS:
            raise StateError("reading", f"expected one of {READINGS}, got {self.reading!r}")
        if not (np.isfinite(self.mu) and self.mu >= 0):
            raise StateError("mu", f"expected a friction coefficient >= 0, got {self.mu!r}")
        if not (np.isfinite(self.mg) and self.mg >= 0):
            raise StateError("mg", f"expected a weight >= 0 (N), got {self.mg!r}")
        if not (0 <= self.state < self.num_states):
            raise StateError(
                "state", f"expected 0 <= state < num_states = {self.num_states}, got {self.state}"
            )


def grid(
    *,
    scenarios: Sequence[str] = ("case2",),
    hands: Sequence[str] = ("default",),
    variants: Sequence[str] = ("L",),
    readings: Sequence[str] = ("physical",),
    mus: Sequence[float] = (0.3,),
    mgs: Sequence[float] = (1.0,),
    states: Sequence[int] | None = None,
    num_states: int = 30,
) -> tuple[SweepPoint, ...]:
    """The full product of the given values (every state of the lift when ``states`` is None)."""
    chosen = range(num_states) if states is None else states
    return tuple(
        SweepPoint(sc, h, v, r, float(mu), float(mg), int(i), num_states)
        for sc, h, v, r, mu, mg, i in itertools.product(
            scenarios, hands, variants, readings, mus, mgs, chosen
        )
    )


@lru_cache(maxsize=8)
def _lift(scenario: str, hand: str, num_states: int) -> Lift:
    return scripted_lift(scenario, variant=hand, num_states=num_states)


@lru_cache(maxsize=512)
def _base(scenario: str, hand: str, num_states: int, index: int) -> GraspState:
    """The MuJoCo grasp of one lift state, shared by every (variant, reading, mu, mg) in this
    worker: only its contact types, friction and REFS differ (``lift_state``'s ``base``)."""
    return lift_state(_lift(scenario, hand, num_states), index)


_Key = tuple[str, str, int, str, str, float, float]


def _solve_group(key: _Key, states: Sequence[int]) -> list[dict[str, Any]]:
    """Solve the given states of one lift configuration (runs in a worker)."""
    scenario, hand, num_states, variant, reading, mu, mg = key
    lift = _lift(scenario, hand, num_states)
    rows = []
    for i in states:
        base = _base(scenario, hand, num_states, i)
        state = lift_state(lift, i, variant=variant, reading=reading, mu=mu, mg=mg, base=base)  # type: ignore[arg-type]
        doc = tvmmp(state, witnesses=False).to_dict(witnesses=False)
        rows.append(
            {
                **asdict(SweepPoint(scenario, hand, variant, reading, mu, mg, i, num_states)),
                "z": float(lift.z[i]),
                **{key: doc[key] for key in ("tvmmp", "feasible", "alpha", "status", "limiting")},
            }
        )
    return rows


def _groups(points: Sequence[SweepPoint], chunk: int) -> list[tuple[_Key, list[int]]]:
    by_key: dict[_Key, list[int]] = {}
    for p in points:
        key = (p.scenario, p.hand, p.num_states, p.variant, p.reading, p.mu, p.mg)
        by_key.setdefault(key, []).append(p.state)
    tasks = []
    for key, states in by_key.items():
        unique = sorted(set(states))
        tasks += [(key, unique[i : i + chunk]) for i in range(0, len(unique), chunk)]
    return tasks


def run_sweep(
    points: Iterable[SweepPoint],
    *,
    jobs: int = 1,
    cluster: Any = None,
    chunk: int = 30,
    progress: bool = True,
) -> list[dict[str, Any]]:
    r"""Solve Problem 2 at every point; rows come back in the order of ``points``.

    Parameters
    ----------
    points
        The sweep (e.g. from :func:`grid`).
    jobs
        Local worker processes (1 = in this process).
    cluster
        A Dask scheduler address (``"tcp://..."``) or a ``distributed.Client``; overrides
        ``jobs``. Needs the ``cluster`` extra (``pip install "mjtvm[cluster]"``).
    chunk
        States per task (tasks of one lift configuration share the worker's lift).
    progress
        Show a tqdm progress bar over tasks.

    Returns
    -------
    list of dict
        One row per point: the point's fields, ``z`` (m), ``tvmmp``, ``feasible``, ``alpha``
        (K x R, null where not optimal), ``status``, ``limiting``.
    """
    pts = list(points)
    if jobs < 1:
        raise StateError("jobs", f"expected a positive number of processes, got {jobs}")
    if chunk < 1:
        raise StateError("chunk", f"expected a positive number of states per task, got {chunk}")
    tasks = _groups(pts, chunk)
    bar = tqdm(total=len(tasks), desc="sweep", unit="task", disable=not progress)
    results: list[list[dict[str, Any]]] = []
    if cluster is not None:
        results = _run_dask(tasks, cluster, bar)
    elif jobs == 1:
        for key, states in tasks:
            results.append(_solve_group(key, states))
            bar.update()
    else:
        context = multiprocessing.get_context("forkserver")
        with ProcessPoolExecutor(max_workers=jobs, mp_context=context) as pool:
            futures = [pool.submit(_solve_group, key, states) for key, states in tasks]
            for f in futures:
                results.append(f.result())
                bar.update()
    bar.close()
    table = {
        (
            r["scenario"],
            r["hand"],
            r["num_states"],
            r["variant"],
            r["reading"],
            r["mu"],
            r["mg"],
            r["state"],
        ): r
        for rows in results
        for r in rows
    }
    return [table[(p.scenario, p.hand, p.num_states, p.variant, p.reading, p.mu, p.mg, p.state)] for p in pts]


def _run_dask(tasks: list[tuple[_Key, list[int]]], cluster: Any, bar: Any) -> list[list[dict[str, Any]]]:
    try:
        from distributed import Client, as_completed
    except ImportError as e:  # pragma: no cover - depends on the optional extra
        raise StateError("cluster", 'Dask is not installed: pip install "mjtvm[cluster]"') from e
    client = cluster if isinstance(cluster, Client) else Client(cluster)
    try:
        futures = client.map(_solve_group, [k for k, _ in tasks], [s for _, s in tasks], pure=False)
        for _ in as_completed(futures):
            bar.update()
        return list(client.gather(futures))
    finally:
        if client is not cluster:
            client.close()
