r"""Constructing a ``highspy.Highs``: highspy imported on first use, its banner kept off standard output.

Every [`HighsSession`][mjtvm.lp.highs.HighsSession] gets its ``Highs`` from
[`new_highs()`][mjtvm.lp.highspy_start.new_highs] (or reuses one a finished session gave back).
"""

from __future__ import annotations

import os
import sys
import threading

__all__ = ["highspy_module", "new_highs"]


def highspy_module():  # type: ignore[no-untyped-def]
    """The ``highspy`` module, imported on first use (``import mjtvm`` does not load HiGHS).

    Returns
    -------
    module
        ``highspy``.
    """
    import highspy

    return highspy


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
