"""Problem 2, the TVMMP: its assembly, LPs, solve, result, diagnosis and dynamic alpha.

[`tvmmp()`][mjtvm.problem2.tvmmp.tvmmp] solves one LP per (REFS, RVDS) pair of a
[`GraspState`][mjtvm.model.state.GraspState] ([`StateLPs`][mjtvm.problem2.lps.StateLPs], built
on [`assemble()`][mjtvm.problem2.assembly.assemble]'s constraint system) and returns a
[`TvmmpResult`][mjtvm.problem2.result.TvmmpResult]; ``diagnosis`` says why an alpha is 0 (it
is imported on first use: it needs scipy's ``linprog``), ``holding`` which motions no joint
holds, ``dynamic`` the alpha with the object's inertia.

This room imports only ``mjtvm.formats``, ``mjtvm.model``, ``mjtvm.lp`` and ``mjtvm.errors``
(import-linter's layers in ``pyproject.toml``).
"""

from mjtvm.problem2.assembly import Assembly, assemble
from mjtvm.problem2.lps import StateLPs
from mjtvm.problem2.result import Diagnosis, Timings, TvmmpResult, Witness
from mjtvm.problem2.tvmmp import tvmmp

__all__ = ["Assembly", "Diagnosis", "StateLPs", "Timings", "TvmmpResult", "Witness", "assemble", "tvmmp"]
