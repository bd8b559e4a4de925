r"""Parameter sweeps of Problem 2 over lifts: a grid, a local process pool or a Dask cluster.

A sweep is a list of [`SweepPoint`][mjtvm.jobs.sweep.SweepPoint] (scenario, hand, contact variant, slide reading,
mu, mg, lift state). Points that share a lift configuration are solved together by one
task, which builds the scripted lift once per worker process (the lift depends only on the
scenario, the hand and the number of states: mu and mg change the statics, not the motion),
reads each state's MuJoCo grasp once per worker, and solves each requested state with
[`tvmmp()`][mjtvm.problem2.tvmmp.tvmmp]. The same tasks run

* serially (``jobs=1``),
* on a local process pool (``jobs > 1``; on Linux forked after this process has built the
  lifts, so that the workers neither import mjtvm nor rebuild a lift; elsewhere started
  from a forkserver, each worker building the lift), or
* on a Dask cluster (``cluster="tcp://host:8786"`` or a ``distributed.Client``), the
  optional ``cluster`` extra. Dask was chosen over Ray because it installs as pure-Python
  wheels from PyPI, its ``LocalCluster`` runs the same code in tests, and ``Client(address)``
  attaches to any existing scheduler (including batch-queue clusters via dask-jobqueue).

Every way returns the same rows in the order of the points (tested). A local pool's workers
never outlive the sweep ([`mjtvm.jobs.pool`][mjtvm.jobs.pool]). A scheduler address is
checked by its handshake within [`CONNECT_TIMEOUT_S`][mjtvm.jobs.sweep.CONNECT_TIMEOUT_S] (`_check_scheduler()`).
The files of ``mjtvm sweep`` (checkpoint, resume, lock) are [`mjtvm.jobs.sweep_files`][mjtvm.jobs.sweep_files].
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from contextlib import contextmanager
from dataclasses import asdict, dataclass
from functools import lru_cache
from typing import Any

import numpy as np
from tqdm import tqdm

from mjtvm.errors import ParamError
from mjtvm.jobs.pool import forks, run_calls
from mjtvm.lift.states import READINGS, VARIANTS, lift_state
from mjtvm.lift.trajectory import Lift, scripted_lift
from mjtvm.model.limits import with_limit_horizon
from mjtvm.model.state import GraspState
from mjtvm.problem2.tvmmp import tvmmp

__all__ = ["SweepPoint", "dask_client", "grid", "point_lift", "point_state", "row_key", "run_sweep"]


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
    limit_horizon
        Problem 2's travel horizon of the joint limits (m); ``None``: the grasp file's.
    """

    scenario: str = "case2"
    hand: str = "default"
    variant: str = "L"
    reading: str = "physical"
    mu: float = 0.3
    mg: float = 1.0
    state: int = 0
    num_states: int = 30
    limit_horizon: float | None = None

    def __post_init__(self) -> None:
        if self.variant not in VARIANTS:
            raise ParamError("variant", f"expected one of {VARIANTS}, got {self.variant!r}")
        if self.reading not in READINGS:
            raise ParamError("reading", f"expected one of {READINGS}, got {self.reading!r}")
        if not (np.isfinite(self.mu) and self.mu >= 0):
            raise ParamError("mu", f"expected a friction coefficient >= 0, got {self.mu!r}")
        if not (np.isfinite(self.mg) and self.mg >= 0):
            raise ParamError("mg", f"expected a weight >= 0 (N), got {self.mg!r}")
        if not (0 <= self.state < self.num_states):
            raise ParamError(
                "state", f"expected 0 <= state < num_states = {self.num_states}, got {self.state}"
            )
        h = self.limit_horizon
        if h is not None and not (np.isfinite(h) and h >= 0):
            raise ParamError("limit_horizon", f"expected a travel horizon >= 0 (m), got {h!r}")


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
    limit_horizon: float | None = None,
) -> tuple[SweepPoint, ...]:
    """The full product of the given values (every state of the lift when ``states`` is None),
    every point with the travel horizon ``limit_horizon`` (``None``: the grasp file's)."""
    chosen = range(num_states) if states is None else states
    return tuple(
        SweepPoint(sc, h, v, r, float(mu), float(mg), int(i), num_states, limit_horizon)
        for sc, h, v, r, mu, mg, i in itertools.product(
            scenarios, hands, variants, readings, mus, mgs, chosen
        )
    )


@lru_cache(maxsize=8)
def point_lift(scenario: str, hand: str, num_states: int) -> Lift:
    """The scripted lift of a sweep's points, built once per process (cached).

    Parameters
    ----------
    scenario, hand
        As in [`SweepPoint`][mjtvm.jobs.sweep.SweepPoint].
    num_states
        Number of states of the lift.

    Returns
    -------
    Lift
        The lift every point of (scenario, hand, num_states) refers to.
    """
    return scripted_lift(scenario, variant=hand, num_states=num_states)


@lru_cache(maxsize=512)
def point_state(scenario: str, hand: str, num_states: int, index: int) -> GraspState:
    """The MuJoCo grasp of one lift state, shared by every (variant, reading, mu, mg) in this
    worker: only its contact types, friction and REFS differ (``lift_state``'s ``base``).

    Parameters
    ----------
    scenario, hand, num_states
        The lift ([`point_lift()`][mjtvm.jobs.sweep.point_lift]).
    index
        The lift state.

    Returns
    -------
    GraspState
        The state's grasp with the grasp file's contact types (cached).
    """
    return lift_state(point_lift(scenario, hand, num_states), index)


_Key = tuple[str, str, int, str, str, float, float, float | None]


def _solve_group(key: _Key, states: Sequence[int]) -> list[dict[str, Any]]:
    """Solve the given states of one lift configuration (runs in a worker)."""
    scenario, hand, num_states, variant, reading, mu, mg, horizon = key
    lift = point_lift(scenario, hand, num_states)
    rows = []
    for i in states:
        base = with_limit_horizon(point_state(scenario, hand, num_states, i), horizon)
        state = lift_state(lift, i, variant=variant, reading=reading, mu=mu, mg=mg, base=base)  # type: ignore[arg-type]
        doc = tvmmp(state, witnesses=False).to_dict(witnesses=False)
        rows.append(
            {
                **asdict(SweepPoint(scenario, hand, variant, reading, mu, mg, i, num_states, horizon)),
                "z": float(lift.z[i]),
                **{key: doc[key] for key in ("tvmmp", "feasible", "alpha", "status", "limiting")},
                "certified": all(c is not False for row in doc["certified"] for c in row),
            }
        )
    return rows


def _groups(points: Sequence[SweepPoint], chunk: int) -> list[tuple[_Key, list[int]]]:
    by_key: dict[_Key, list[int]] = {}
    for p in points:
        key = (p.scenario, p.hand, p.num_states, p.variant, p.reading, p.mu, p.mg, p.limit_horizon)
        by_key.setdefault(key, []).append(p.state)
    tasks = []
    for key, states in by_key.items():
        unique = sorted(set(states))
        tasks += [(key, unique[i : i + chunk]) for i in range(0, len(unique), chunk)]
    return tasks


def row_key(r: dict[str, Any] | SweepPoint) -> _RowKey:
    """The identity of a row or point: what a checkpointed row must match to be kept.

    Parameters
    ----------
    r
        A row of [`run_sweep()`][mjtvm.jobs.sweep.run_sweep] (or of an earlier version's
        file) or a point.

    Returns
    -------
    tuple
        (scenario, hand, num_states, variant, reading, mu, mg, state, limit_horizon).
    """
    if isinstance(r, SweepPoint):
        return (r.scenario, r.hand, r.num_states, r.variant, r.reading, r.mu, r.mg, r.state, r.limit_horizon)
    return (  # a row of an earlier version, without the field, had the grasp file's horizon
        r["scenario"],
        r["hand"],
        r["num_states"],
        r["variant"],
        r["reading"],
        r["mu"],
        r["mg"],
        r["state"],
        r.get("limit_horizon"),
    )


_RowKey = tuple[str, str, int, str, str, float, float, int, float | None]


def run_sweep(
    points: Iterable[SweepPoint],
    *,
    jobs: int = 1,
    cluster: Any = None,
    chunk: int = 30,
    progress: bool = True,
    done: Mapping[_RowKey, dict[str, Any]] | None = None,
    on_rows: Callable[[list[dict[str, Any]]], None] | None = None,
) -> list[dict[str, Any]]:
    r"""Solve Problem 2 at every point; rows come back in the order of ``points``.

    Parameters
    ----------
    points
        The sweep (e.g. from [`grid()`][mjtvm.jobs.sweep.grid]).
    jobs
        Local worker processes (1 = in this process).
    cluster
        A Dask scheduler address (``"tcp://..."``) or a ``distributed.Client``; overrides
        ``jobs``. Needs the ``cluster`` extra (``pip install "mjtvm[cluster]"``).
    chunk
        States per task, at most. On a Dask cluster or a forkserver pool a task is one
        configuration of a lift (they share the worker's lift); on a forked pool (Linux) a
        task solves every configuration of a lift at its states, about 8 tasks per worker.
        In this process (``jobs=1``) every state is its own task: the lift is cached anyway,
        and ``on_rows`` then sees every row as soon as it exists.
    progress
        Show a tqdm progress bar over the rows to compute.
    done
        Rows already computed (e.g. read from a checkpoint), keyed by their point: these
        points are not solved again and their rows are returned as given.
    on_rows
        Called with the rows of every finished task, in this process (checkpointing).

    Returns
    -------
    list of dict
        One row per point: the point's fields, ``z`` (m), ``tvmmp``, ``feasible``, ``alpha``
        (K x R, null where not optimal), ``status``, ``limiting``.

    Raises
    ------
    ParamError
        ``jobs`` or ``chunk`` below 1, or a ``cluster`` that cannot be reached.
    """
    pts = list(points)
    if jobs < 1:
        raise ParamError("jobs", f"expected a positive number of processes, got {jobs}")
    if chunk < 1:
        raise ParamError("chunk", f"expected a positive number of states per task, got {chunk}")
    table: dict[_RowKey, dict[str, Any]] = dict(done or {})
    todo = [p for p in pts if row_key(p) not in table]
    serial = cluster is None and jobs == 1
    tasks = _groups(todo, 1 if serial else chunk)
    bar = tqdm(total=len(todo), desc="sweep", unit="row", disable=not progress)

    def finished(rows: list[dict[str, Any]]) -> None:
        table.update((row_key(r), r) for r in rows)
        if on_rows is not None:
            on_rows(rows)
        bar.update(len(rows))

    try:
        if cluster is not None:
            _run_dask(tasks, cluster, finished)
        elif serial:
            for key, states in tasks:
                finished(_solve_group(key, states))
        else:
            _run_pool(tasks, jobs, finished)
    finally:
        bar.close()
    return [table[row_key(p)] for p in pts]


def _fork_tasks(tasks: list[tuple[_Key, list[int]]], jobs: int) -> list[list[tuple[_Key, list[int]]]]:
    """The work regrouped for forked workers: per lift, its states dealt round-robin into
    about 8 tasks per worker (a state's cost varies along the lift), each task solving every
    configuration of the lift at its states, so that a state's MuJoCo grasp (``point_state``) is
    read in one worker only. Task sizes never exceed the given tasks' states."""
    by_lift: dict[tuple[str, str, int], dict[_Key, set[int]]] = {}
    size = max((len(states) for _, states in tasks), default=1)
    for key, states in tasks:
        by_lift.setdefault((key[0], key[1], key[2]), {}).setdefault(key, set()).update(states)
    out = []
    for configs in by_lift.values():
        states = sorted(set().union(*configs.values()))
        n = max(min(len(states), 8 * jobs), -(-len(states) // size))
        for part in (set(states[t::n]) for t in range(n)):
            out.append([(key, sorted(part & wanted)) for key, wanted in configs.items() if part & wanted])
    return out


def _solve_many(groups: list[tuple[_Key, list[int]]]) -> list[dict[str, Any]]:
    """`_solve_group()` of each group (one forked task)."""
    return [row for key, states in groups for row in _solve_group(key, states)]


def _run_pool(
    tasks: list[tuple[_Key, list[int]]], jobs: int, finished: Callable[[list[dict[str, Any]]], None]
) -> None:
    """The tasks on ``jobs`` local processes.

    On Linux the lifts are built here and the workers are forked afterwards: they start with
    mjtvm imported and the lifts in memory (the lift is the sweep's serial part; before, the
    forkserver's workers imported mjtvm and built it again each). Forking is safe here: at
    that point the process's only other threads are OpenBLAS' idle pools, which OpenBLAS
    re-creates in the child (pthread_atfork); HiGHS runs single-threaded and its idle
    instances are not reused across the fork ([`mjtvm.lp.highs`][mjtvm.lp.highs]); MuJoCo holds no
    threads. Elsewhere (no safe fork) the forkserver's workers build the lift themselves.
    """
    fork = forks()
    calls: list[tuple[Callable[..., list[dict[str, Any]]], tuple[Any, ...]]]
    if fork:
        for key in {(k[0], k[1], k[2]) for k, _ in tasks}:
            point_lift(*key)
        calls = [(_solve_many, (groups,)) for groups in _fork_tasks(tasks, jobs)]
    else:
        calls = [(_solve_group, (key, states)) for key, states in tasks]
    run_calls(calls, jobs, finished, fork=fork)


CONNECT_TIMEOUT_S = 10.0
"""How long [`run_sweep()`][mjtvm.jobs.sweep.run_sweep] waits for a Dask scheduler given by address."""


def _check_scheduler(address: str, timeout: float) -> None:
    """Connect to ``address`` and read the scheduler's handshake, all within ``timeout`` s.

    ``distributed.Client`` bounds only the TCP connection by its timeout: a server that
    accepts and then stays silent keeps it waiting for the handshake without end, and one that
    answers in another protocol makes it fail with whatever its decoder raises (a 2 EiB
    allocation, a struct error).

    Raises
    ------
    ParamError
        Nothing answers within ``timeout`` s, or the server there is not a Dask scheduler.
    """
    import asyncio

    from distributed.comm import connect

    async def handshake() -> None:
        comm = await connect(address, timeout=timeout)
        await comm.close()

    try:
        asyncio.run(asyncio.wait_for(handshake(), timeout))
    except (OSError, TimeoutError) as e:  # refused, unreachable, or no handshake in time
        why = str(e).splitlines()[0][:200] if str(e) else "no Dask handshake from the server there"
        raise ParamError(
            "cluster", f"cannot reach a Dask scheduler at {address} within {timeout:g} s ({why})"
        ) from e
    except Exception as e:  # whatever the handshake's decoder makes of another protocol
        raise ParamError(
            "cluster",
            f"expected a Dask scheduler at {address}, but the server there answers in another "
            f"protocol ({type(e).__name__} on its handshake)",
        ) from e


@contextmanager
def dask_client(cluster: Any) -> Iterator[Any]:
    """A Dask client of ``cluster``: a ``distributed.Client`` as it is, or a scheduler address
    checked (`_check_scheduler()`), connected, and closed on exit.

    Raises
    ------
    ParamError
        Dask is not installed, or no Dask scheduler answers at the address.
    """
    try:
        from distributed import Client
    except ImportError as e:  # pragma: no cover - depends on the optional extra
        raise ParamError("cluster", 'Dask is not installed: pip install "mjtvm[cluster]"') from e
    if isinstance(cluster, Client):
        yield cluster
        return
    _check_scheduler(cluster, CONNECT_TIMEOUT_S)
    try:
        client = Client(cluster, timeout=f"{CONNECT_TIMEOUT_S}s")
    except (OSError, TimeoutError, ValueError) as e:
        raise ParamError(
            "cluster",
            f"cannot reach a Dask scheduler at {cluster} within {CONNECT_TIMEOUT_S:g} s ({e})",
        ) from e
    try:
        yield client
    finally:
        client.close()


def _run_dask(
    tasks: list[tuple[_Key, list[int]]], cluster: Any, finished: Callable[[list[dict[str, Any]]], None]
) -> None:
    from distributed import as_completed

    with dask_client(cluster) as client:
        futures = client.map(_solve_group, [k for k, _ in tasks], [s for _, s in tasks], pure=False)
        for fut in as_completed(futures):
            finished(fut.result())
