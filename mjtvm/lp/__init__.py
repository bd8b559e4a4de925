"""The LP engine: linear programs, their HiGHS and Clarabel solves, and their certificates.

A [`LinearProgram`][mjtvm.lp.lp.LinearProgram] is equilibrated (``scaling``), its round-off
dropped (``roundoff``), solved by HiGHS ([`HighsSession`][mjtvm.lp.highs.HighsSession], one
session re-solved per change) or Clarabel, and every answer checked on the unscaled LP
([`certify()`][mjtvm.lp.certificate.certify], the batch checker ``certifier``).
``solvers`` gathers what Problem 2 calls.

This room imports only ``mjtvm.errors`` (import-linter's layers in ``pyproject.toml``).
"""

from mjtvm.lp.certificate import Certificate, certify
from mjtvm.lp.clarabel import solve_clarabel
from mjtvm.lp.highs import HighsSession
from mjtvm.lp.lp import LinearProgram, LPSolution

__all__ = ["Certificate", "HighsSession", "LPSolution", "LinearProgram", "certify", "solve_clarabel"]
