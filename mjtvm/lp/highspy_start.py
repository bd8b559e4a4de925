r"""Constructing a ``highspy.Highs``: highspy imported on first use, its banner kept off standard output.

Every [`HighsSession`][mjtvm.lp.highs.HighsSession] gets its ``Highs`` from
[`new_highs()`][mjtvm.lp.highspy_start.new_highs], or reuses one a finished session gave back
([`give_back()`][mjtvm.lp.highspy_start.give_back], [`acquire_highs()`][mjtvm.lp.highspy_start.acquire_highs]);
every ``run`` is timed for [`observe_runs()`][mjtvm.lp.highspy_start.observe_runs]' callbacks.
"""

from __future__ import annotations

import os
import sys
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import Any

__all__ = ["acquire_highs", "give_back", "highspy_module", "new_highs", "observe_runs", "ran"]


def highspy_module():  # type: ignore[no-untyped-def]
    """The ``highspy`` module, imported on first use (``import mjtvm`` does not load HiGHS).

    Returns
    -------
    module
        ``highspy``.
    """
    import highspy

    return highspy


#: Callbacks told the wall time (s) of every HiGHS ``run`` of every session (observe_runs).
_RUN_OBSERVERS: list[Callable[[float], None]] = []


@contextmanager
def observe_runs(callback: Callable[[float], None]) -> Iterator[None]:
    """Call ``callback(seconds)`` after every HiGHS ``run`` of every [`HighsSession`][mjtvm.lp.highs.HighsSession]
    while the context is open: the one hook for a progress count (``mjtvm tvms``) and for the
    benchmark's time inside HiGHS, instead of each patching ``highspy.Highs.run``."""
    _RUN_OBSERVERS.append(callback)
    try:
        yield
    finally:
        _RUN_OBSERVERS.remove(callback)


def ran(started: float) -> None:
    """Tell the observers (`observe_runs()`) of a HiGHS ``run`` begun at ``started``
    (``time.perf_counter()``) that it has ended."""
    if _RUN_OBSERVERS:
        spent = time.perf_counter() - started
        for observer in tuple(_RUN_OBSERVERS):
            observer(spent)


_FD_LOCK = threading.Lock()


def new_highs():  # type: ignore[no-untyped-def]
    """A new ``highspy.Highs`` whose start-up banner does not reach standard output.

    highspy >= 1.16 writes "Running HiGHS ..." to file descriptor 1 from C++ when the first
    ``Highs`` of a process is constructed, before any option (``output_flag``) can be set;
    that breaks every JSON consumer of ``mjtvm solve``. File descriptor 1 is pointed at
    ``/dev/null`` for the construction only (Python's own buffered output is flushed first,
    so nothing of ours is lost); where descriptors cannot be duplicated it is left alone.
    """
    highspy = highspy_module()
    with _FD_LOCK:
        try:
            sys.stdout.flush()
        except (OSError, ValueError):  # closed or broken stdout: nothing of ours to keep
            pass
        try:
            saved = os.dup(1)
        except OSError:  # no descriptor 1 at all: nothing to protect
            return highspy.Highs()
        try:
            devnull = os.open(os.devnull, os.O_WRONLY)
            try:
                os.dup2(devnull, 1)
            finally:
                os.close(devnull)
            return highspy.Highs()
        finally:
            os.dup2(saved, 1)
            os.close(saved)


_IDLE: list[Any] = []  # Highs instances given back by finished sessions (give_back), this process's
_IDLE_PID = [os.getpid()]
_IDLE_MAX = 4


def acquire_highs():  # type: ignore[no-untyped-def]
    """An idle ``Highs`` given back by [`give_back()`][mjtvm.lp.highspy_start.give_back] (a finished
    session's, [`HighsSession.release()`][mjtvm.lp.highs.HighsSession.release]), else
    [`new_highs()`][mjtvm.lp.highspy_start.new_highs].

    Constructing a ``Highs`` costs ~50 us, 2 % of a Problem 2 state; a reused one gets a new
    model (``passModel`` discards the old model, basis and solution) and the session's options,
    so its solves are the same, bit for bit (tested). Instances are never shared across a
    fork: the list is emptied when the process id changes."""
    if _IDLE_PID[0] != os.getpid():
        _IDLE.clear()
        _IDLE_PID[0] = os.getpid()
    try:
        return _IDLE.pop()
    except IndexError:
        return new_highs()


def give_back(h: Any) -> None:
    """Keep the ``Highs`` ``h``, which its session no longer uses, for
    [`acquire_highs()`][mjtvm.lp.highspy_start.acquire_highs] in this process (at most
    ``_IDLE_MAX`` kept; none kept across a fork)."""
    if len(_IDLE) < _IDLE_MAX and _IDLE_PID[0] == os.getpid():
        _IDLE.append(h)
