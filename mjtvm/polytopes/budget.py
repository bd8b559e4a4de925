r"""Limits of an anytime projection (Problem 1): memory, time and the volume tolerance.

`Limits` is what [`tvms()`][mjtvm.polytopes.tvms.tvms] passes down to
`project_lp()`: a relative volume tolerance (0: exact within
floating point), a wall-clock limit and a memory budget. [`Budget`][mjtvm.polytopes.budget.Budget] enforces them:
[`Budget.reserve()`][mjtvm.polytopes.budget.Budget.reserve] is called with the size of an array (or a Qhull hull) *before* it is
made, and [`Budget.check()`][mjtvm.polytopes.budget.Budget.check] between steps; both raise [`LimitReached`][mjtvm.polytopes.budget.LimitReached], which the
projection turns into ``status: "approximate"`` with the bracket it has.

The memory budget counts the resident set of the process above what it held when the solve
started (Linux ``/proc/self/statm``; elsewhere only the announced sizes), so HiGHS' and Qhull's
own buffers count too. The default is [`DEFAULT_MEMORY_FRACTION`][mjtvm.polytopes.budget.DEFAULT_MEMORY_FRACTION] of the memory the
machine has available (``MemAvailable`` in ``/proc/meminfo``, else psutil when installed,
else the physical memory).
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from mjtvm.errors import ParamError

__all__ = [
    "DEFAULT_CONFIDENCE",
    "DEFAULT_MEMORY_FRACTION",
    "Budget",
    "LimitReached",
    "Limits",
    "available_memory",
    "default_memory_budget",
    "rss_bytes",
]

DEFAULT_MEMORY_FRACTION = 0.25  #: of the available memory: the default budget
DEFAULT_CONFIDENCE = 0.999  #: of the randomized estimate's interval (``tvms(confidence=...)``)


def available_memory() -> int:
    """Bytes of memory available to new allocations (``MemAvailable``; see the module docstring)."""
    try:
        with open("/proc/meminfo", encoding="ascii") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    try:
        import psutil

        return int(psutil.virtual_memory().available)
    except ImportError:
        pass
    try:
        return int(os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES"))
    except (ValueError, OSError, AttributeError):
        return 4 * 2**30


def default_memory_budget() -> int:
    """[`DEFAULT_MEMORY_FRACTION`][mjtvm.polytopes.budget.DEFAULT_MEMORY_FRACTION] of [`available_memory()`][mjtvm.polytopes.budget.available_memory], in bytes."""
    return int(DEFAULT_MEMORY_FRACTION * available_memory())


def rss_bytes() -> int:
    """The process's current resident set in bytes (0 where ``/proc/self/statm`` is missing)."""
    try:
        with open("/proc/self/statm", encoding="ascii") as f:
            return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")
    except (OSError, ValueError, IndexError):
        return 0


class LimitReached(Exception):
    """A limit of `Limits` stops the projection: ``reason`` is ``"time"`` or ``"memory"``."""

    def __init__(self, reason: str, detail: str) -> None:
        super().__init__(f"{reason} limit: {detail}")
        self.reason, self.detail = reason, detail


@dataclass(frozen=True)
class Limits:
    r"""When an anytime projection stops before it is exact.

    Attributes
    ----------
    tolerance
        Stop when ``(outer - inner) / outer`` of the volume bracket is at most this (0: run
        until exact within floating point; the bracket is then measured only at the end).
    time_limit
        Seconds of wall-clock time for the whole solve (``None``: none).
    memory
        Bytes of memory the solve may add to the process (``None``: `default_memory_budget()`).
    progress
        Called with a dict (``round``, ``lps``, ``inner``, ``outer``, ``gap``, ``hausdorff``,
        ``seconds``) whenever the bracket is measured, and (``phase: "estimate"``,
        ``samples``, ``lower``, ``upper``, ``width``, ``lps``, ``seconds``) after each batch
        of the randomized estimate; ``None``: nothing.
    confidence
        With a ``tolerance``: when the certified bracket stays wider, a randomized estimate
        ([`estimate`][mjtvm.polytopes.estimate]) whose interval holds the volume with this
        probability; 0: none.
    """

    tolerance: float = 0.0
    time_limit: float | None = None
    memory: int | None = None
    progress: Callable[[dict[str, Any]], None] | None = None
    confidence: float = 0.0

    def __post_init__(self) -> None:
        if not (0.0 <= self.tolerance < 1.0):
            raise ParamError("tolerance", f"expected a number in [0, 1), got {self.tolerance!r}")
        if self.time_limit is not None and not self.time_limit > 0.0:
            raise ParamError("time_limit", f"expected a positive number of seconds, got {self.time_limit!r}")
        if self.memory is not None and not self.memory > 0:
            raise ParamError("memory", f"expected a positive number of bytes, got {self.memory!r}")
        if not (0.0 <= self.confidence < 1.0):
            raise ParamError("confidence", f"expected a probability in [0, 1), got {self.confidence!r}")


class Budget:
    """The running account of `Limits` for one solve (started at construction)."""

    def __init__(self, limits: Limits | None = None) -> None:
        self.limits = limits or Limits()
        self.start = time.perf_counter()
        self.base_rss = rss_bytes()
        self.memory = self.limits.memory if self.limits.memory is not None else default_memory_budget()
        self.peak = 0  #: the largest use (bytes above the start) seen by reserve / check
        #: seconds after the start at which `check()` stops (default: the time limit)
        self.deadline: float | None = self.limits.time_limit

    @property
    def elapsed(self) -> float:
        """Seconds since the start."""
        return time.perf_counter() - self.start

    def used(self) -> int:
        """Bytes of resident set above the start."""
        return max(rss_bytes() - self.base_rss, 0)

    def reserve(self, nbytes: float, what: str) -> None:
        """Raise [`LimitReached`][mjtvm.polytopes.budget.LimitReached] if ``nbytes`` more would exceed the memory budget."""
        used = self.used()
        self.peak = max(self.peak, used)
        if used + nbytes > self.memory:
            raise LimitReached(
                "memory",
                f"{what} needs {nbytes / 2**20:.0f} MiB with {used / 2**20:.0f} MiB in use "
                f"(budget {self.memory / 2**20:.0f} MiB)",
            )

    def check(self) -> None:
        """Raise [`LimitReached`][mjtvm.polytopes.budget.LimitReached] past the time limit or the memory budget."""
        t = self.deadline
        if t is not None and self.elapsed > t:
            raise LimitReached("time", f"{self.elapsed:.1f} s > {t:g} s")
        self.reserve(0, "the solve")

    def chunk_rows(self, row_bytes: float, *, share: float = 0.25, cap: int = 1 << 20) -> int:
        """How many rows of ``row_bytes`` bytes one block may hold: ``share`` of what the budget
        has left (at least 1, at most ``cap``)."""
        free = max(self.memory - self.used(), 0) * share
        return int(max(1, min(cap, free // max(row_bytes, 1.0))))
