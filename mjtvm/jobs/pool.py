r"""Local process pools of the jobs: how a worker starts, how a pool is stopped, which start method.

[`run_calls()`][mjtvm.jobs.pool.run_calls] runs calls on a local pool (forked on Linux, where
[`forks()`][mjtvm.jobs.pool.forks], else started from a forkserver). A pool's workers never
outlive the job: an interrupt ends them at once ([`stop()`][mjtvm.jobs.pool.stop]), and on
Linux the kernel kills them when their parent dies
([`die_with_parent()`][mjtvm.jobs.pool.die_with_parent], armed by
[`init_worker()`][mjtvm.jobs.pool.init_worker]). The sweep, the ranking and the physics check
share them.
"""

from __future__ import annotations

import multiprocessing
import os
import signal
import sys
import time
import warnings
from collections.abc import Callable, Iterable
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from itertools import islice
from typing import Any

__all__ = ["STOP_WAIT_S", "die_with_parent", "forks", "init_worker", "run_calls", "stop"]

_PR_SET_PDEATHSIG = 1
"""``prctl`` option (``<linux/prctl.h>``): the signal a process gets when its parent ends."""

STOP_WAIT_S = 1.0
"""How long an interrupted pool's workers get to end on SIGTERM before they are killed."""


def die_with_parent() -> None:
    """Have the kernel kill this process when its parent ends (Linux; elsewhere nothing).

    A pool worker blocks on its task queue, which its siblings hold open too: it would never
    notice a parent killed by SIGKILL, and would live on as an orphan.
    """
    if not sys.platform.startswith("linux"):
        return
    import ctypes

    try:
        libc = ctypes.CDLL(None, use_errno=True)
        libc.prctl(_PR_SET_PDEATHSIG, signal.SIGKILL, 0, 0, 0)
    except (OSError, AttributeError):  # pragma: no cover - a libc without prctl
        return


def init_worker(parent: int = 0) -> None:
    """Set up a pool worker (a pool's ``initializer``).

    Ctrl-C is the parent's (a terminal sends SIGINT to the whole process group; each worker
    would print its own KeyboardInterrupt traceback), and the worker dies with its parent
    ([`die_with_parent()`][mjtvm.jobs.pool.die_with_parent]).

    Parameters
    ----------
    parent
        The pid of the process that forked the worker (0 for a forkserver's worker, whose
        parent is the forkserver).
    """
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    die_with_parent()
    if parent and os.getppid() != parent:  # the parent ended before the death signal was armed
        os._exit(1)


def stop(pool: ProcessPoolExecutor) -> None:
    """Cancel the pending tasks and end the workers now.

    ``shutdown(wait=True)``, what the ``with`` statement does, would first run every queued
    task; ``shutdown`` also forgets the workers, so they are taken before it. Workers get
    SIGTERM, and SIGKILL after [`STOP_WAIT_S`][mjtvm.jobs.pool.STOP_WAIT_S].

    Parameters
    ----------
    pool
        The pool to end.
    """
    procs = list((getattr(pool, "_processes", None) or {}).values())
    pool.shutdown(wait=False, cancel_futures=True)
    for proc in procs:
        proc.terminate()
    deadline = time.monotonic() + STOP_WAIT_S
    for proc in procs:
        proc.join(max(0.0, deadline - time.monotonic()))
        if proc.is_alive():
            proc.kill()
            proc.join(STOP_WAIT_S)


def forks() -> bool:
    """Whether local pools fork their workers (Linux) rather than start them from a forkserver.

    Returns
    -------
    bool
        ``True`` on Linux with the ``fork`` start method available.
    """
    return sys.platform.startswith("linux") and "fork" in multiprocessing.get_all_start_methods()


def run_calls(
    calls: Iterable[tuple[Callable[..., list[dict[str, Any]]], tuple[Any, ...]]],
    jobs: int,
    finished: Callable[[list[dict[str, Any]]], None],
    *,
    fork: bool,
    in_order: bool = True,
    window: int | None = None,
) -> None:
    """Each ``fn(*args)`` of ``calls`` on ``jobs`` local processes (forked, or started from a
    forkserver), its rows passed to ``finished`` in the order of ``calls`` or, without
    ``in_order``, as they finish. Without ``in_order`` at most ``window`` calls (default
    ``4 * jobs``) are pending at a time and ``calls`` is read as they go: a lazy iterable's
    tasks are never all held. On an interrupt or a failure the pending calls are cancelled
    and the workers ended ([`stop()`][mjtvm.jobs.pool.stop])."""
    context = multiprocessing.get_context("fork" if fork else "forkserver")
    pool = ProcessPoolExecutor(
        max_workers=jobs, mp_context=context, initializer=init_worker, initargs=(os.getpid() if fork else 0,)
    )
    try:
        with warnings.catch_warnings():
            # Python >= 3.12 warns about fork() beside other threads: OpenBLAS' (see
            # mjtvm.jobs.sweep's pool).
            warnings.filterwarnings("ignore", "This process .* is multi-threaded", DeprecationWarning)
            if in_order:
                futures = [pool.submit(fn, *args) for fn, args in calls]
                for f in futures:
                    finished(f.result())
            else:
                todo = iter(calls)
                pending: set[Future[list[dict[str, Any]]]] = set()
                limit = max(1, window or 4 * jobs)
                while True:
                    for fn, args in islice(todo, limit - len(pending)):
                        pending.add(pool.submit(fn, *args))
                    if not pending:
                        break
                    done, pending = wait(pending, return_when=FIRST_COMPLETED)
                    for f in done:
                        finished(f.result())
    except BaseException:
        stop(pool)
        raise
    pool.shutdown()
