"""The shortcuts of Problem 2's per-state work (issue 15, item 5) give the very same numbers.

Each fast path is compared with the generic code it replaces, to the bit: the assembly's
CSC built by sorting (scipy's COO conversion), the first LP's equilibrated matrix built from
the per-state scaled matrix (``scale_lp`` of ``lp``, round-off drop included), and a HiGHS
instance reused by the next state (a fresh one).
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp

from mjtvm import ParamError, tvmmp
from mjtvm.formats.state_file import load_state
from mjtvm.lp import highs, highspy_start
from mjtvm.lp.rows import Coo
from mjtvm.lp.scaling import scale_lp
from mjtvm.paper_hand.scenario import load_scenario
from mjtvm.problem2.assembly import assemble
from mjtvm.problem2.lps import StateLPs
from tests.lp.test_solvers import mixed_scale

from .test_units import rescale

EXAMPLE = Path(__file__).resolve().parents[2] / "mjtvm" / "data" / "examples" / "pinch.json"


@pytest.fixture(scope="module")
def states():
    pinch = load_state(EXAMPLE)
    case2 = load_scenario("case2").state()
    return {
        "pinch": pinch,
        "case2": case2,
        "case2_tiny_units": rescale(case2, length=1e6, force=1e-6, time=1e3),
        "pinch_mixed_scale": mixed_scale(pinch, 7),  # entries 1e-8 and 1e4: round-off drops happen
        "case2_preload": case2.with_(
            contacts=tuple(replace(c, preload=0.05) if c.type != "D" else c for c in case2.contacts)
        ),
    }


def _same_csc(a: sp.csc_matrix, b: sp.csc_matrix) -> None:
    assert a.shape == b.shape
    assert a.indptr.dtype == b.indptr.dtype and a.indices.dtype == b.indices.dtype
    np.testing.assert_array_equal(a.indptr, b.indptr)
    np.testing.assert_array_equal(a.indices, b.indices)
    np.testing.assert_array_equal(a.data, b.data)


def test_sorted_csc_is_scipys_conversion(states):
    for state in states.values():
        for kwargs in ({}, {"box": "literal"}, {"copies": 2}):
            asm = assemble(state, **kwargs)  # type: ignore[arg-type]
            for m in (asm.A, asm.A_twist):
                coo = m.tocoo()
                _same_csc(m, sp.csc_matrix((coo.data, (coo.row, coo.col)), shape=m.shape))


def test_repeated_entries_are_still_summed():
    coo = Coo()
    coo.add(0, 0, np.array([[1.0, 2.0], [0.0, 3.0]]))
    coo.add(1, 1, np.array([[0.5]]))
    np.testing.assert_array_equal(coo.build((2, 2)).toarray(), [[1.0, 2.0], [0.0, 3.5]])


def test_first_lp_equals_scale_lp(states):
    for state in states.values():
        problem = StateLPs(state, "eliminated", "highs")
        for r in state.rvds:
            lp, s = problem.lp(state.refs[0], r)
            generic = scale_lp(lp, s)
            session = problem._session(state.refs[0], r, np.inf)
            ref = highs.HighsSession(lp, scaling=s)
            for name in ("col_cost_", "col_lower_", "col_upper_", "row_lower_", "row_upper_"):
                np.testing.assert_array_equal(
                    getattr(session.highs.getLp(), name), getattr(ref.highs.getLp(), name)
                )
            fast = session.highs.getLp().a_matrix_
            np.testing.assert_array_equal(fast.start_, generic.A.indptr)
            np.testing.assert_array_equal(fast.index_, generic.A.indices)
            np.testing.assert_array_equal(fast.value_, generic.A.data)
            np.testing.assert_array_equal(session._row_max, ref._row_max)


def test_a_reused_highs_instance_solves_bit_for_bit(states, monkeypatch):
    monkeypatch.setattr(highspy_start, "_IDLE", [])
    fresh = {name: tvmmp(state) for name, state in states.items()}
    assert highspy_start._IDLE  # the sessions gave their instances back
    for name in reversed(list(states)):  # every state now on another state's instance
        again = tvmmp(states[name])
        np.testing.assert_array_equal(again.alpha, fresh[name].alpha)
        assert again.status == fresh[name].status and again.notes == fresh[name].notes
        for row_a, row_b in zip(again.witnesses, fresh[name].witnesses):
            for a, b in zip(row_a, row_b):
                assert (a is None) == (b is None)
                if a is not None:
                    np.testing.assert_array_equal(a.forces, b.forces)
                    np.testing.assert_array_equal(a.speeds, b.speeds)


def test_the_idle_instances_stay_in_their_process(monkeypatch):
    import highspy

    monkeypatch.setattr(highspy_start, "_IDLE", ["an instance of the parent"])
    monkeypatch.setattr(highspy_start, "_IDLE_PID", [-1])  # as after a fork
    assert isinstance(highspy_start.acquire_highs(), highspy.Highs)
    assert highspy_start._IDLE == []


def test_the_tuned_highs_options_are_highs_defaults_elsewhere():
    """Every session sets the options a session may tune, at HiGHS' own defaults unless
    tuned: a ``Highs`` reused after Problem 2 solves other LPs as a fresh one."""
    fresh = highs.new_highs()
    for name, value in highs._TUNABLE_DEFAULTS.items():
        assert fresh.getOptionValue(name)[1] == value
    with pytest.raises(ParamError, match=r"^options: "):
        highs.HighsSession.from_scaled(*_one_lp(), options={"presolve": "on"})


def _one_lp():  # type: ignore[no-untyped-def]
    from mjtvm.lp.solvers import LinearProgram, Scaling

    lp = LinearProgram(
        np.array([-1.0]), sp.csc_matrix(np.ones((1, 1))), np.zeros(1), np.ones(1), np.zeros(1), np.ones(1)
    )
    return lp, Scaling(np.ones(1), np.ones(1)), lp.c, lp.col_lower, lp.col_upper


@pytest.mark.parametrize("box", ["eliminated", "literal"])
def test_tuned_highs_options_give_the_default_alphas(states, box, monkeypatch):
    """Problem 2's HiGHS options (problem2.P2_HIGHS_OPTIONS: Devex dual edge weights) reach
    the same vertices as HiGHS' defaults along another path: the same statuses, alphas
    within 1e-9 relative (1e-11 measured), on the fixtures and on random states."""
    from benchmarks.synthetic import random_state
    from mjtvm.problem2 import lps as problem2_module

    cases = dict(states)
    for seed, types in enumerate(
        [("F", "L", "F", "L", "D"), ("L", "S", "L", "S", "D"), ("F", "F", "L", "S", "D")]
    ):
        cases[f"random{seed}"] = random_state(seed, contact_types=types, num_refs=2)
    tuned = {name: tvmmp(state, box=box, witnesses=False) for name, state in cases.items()}
    monkeypatch.setattr(problem2_module, "P2_HIGHS_OPTIONS", {})
    for name, state in cases.items():
        default = tvmmp(state, box=box, witnesses=False)
        assert tuned[name].status == default.status, name
        np.testing.assert_allclose(tuned[name].alpha, default.alpha, rtol=1e-9, atol=0.0, err_msg=name)


@pytest.mark.parametrize("box", ["eliminated", "literal"])
def test_the_start_basis_gives_the_slack_basis_alphas(states, box, monkeypatch):
    """The first LP of a state starts from the torques basic in their rows
    (HighsSession.start_basis) rather than from HiGHS' slack basis: the same statuses and
    alphas within 1e-9 relative, on the fixtures and on random states."""
    from benchmarks.synthetic import random_state

    cases = dict(states)
    for seed, types in enumerate(
        [("F", "L", "F", "L", "D"), ("L", "S", "L", "S", "D"), ("F", "F", "L", "S", "D")]
    ):
        cases[f"random{seed}"] = random_state(seed, contact_types=types, num_refs=2)
    started = {name: tvmmp(state, box=box, witnesses=False) for name, state in cases.items()}
    monkeypatch.setattr(highs.HighsSession, "start_basis", lambda self, cols, rows: None)
    for name, state in cases.items():
        slack = tvmmp(state, box=box, witnesses=False)
        assert started[name].status == slack.status, name
        np.testing.assert_allclose(started[name].alpha, slack.alpha, rtol=1e-9, atol=0.0, err_msg=name)


def test_start_basis_needs_as_many_columns_as_rows():
    session = highs.HighsSession.from_scaled(*_one_lp())
    with pytest.raises(ParamError, match=r"^start_basis: as many"):
        session.start_basis(np.array([0]), np.array([], dtype=np.int64))
    session.start_basis(np.array([0]), np.array([0]))
    assert session.solve().objective == pytest.approx(-1.0)


def test_large_state_certificates_take_the_pattern_from_the_sparse_matrix(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """The 32-finger scaling hand's matrix is past BATCH_ENTRIES: its certificates' nonzero
    products take their pattern from the assembly's stored entries (once per state); every
    certificate and alpha is the same, bit for bit, as with the pattern scanned from the dense
    matrix (the Certifier given no ``pattern``)."""
    from benchmarks.scaling import scaling_hand
    from mjtvm.lp import certifier, nonzero

    state = scaling_hand(32)
    calls: list[str] = []
    certificates: list[object] = []
    entries, scan, check_many = (
        nonzero.NonzeroProducts.from_entries.__func__,  # type: ignore[attr-defined]
        nonzero.NonzeroProducts.__init__,
        certifier.Certifier.check_many,
    )

    def from_entries(cls, shape, rows, cols):  # type: ignore[no-untyped-def]
        calls.append("entries")
        return entries(cls, shape, rows, cols)

    def init(self, pattern):  # type: ignore[no-untyped-def]
        calls.append("scan")
        scan(self, pattern)

    def recorded(self, *args, **kwargs):  # type: ignore[no-untyped-def]
        out = check_many(self, *args, **kwargs)
        certificates.append(out)
        return out

    monkeypatch.setattr(nonzero.NonzeroProducts, "from_entries", classmethod(from_entries))
    monkeypatch.setattr(nonzero.NonzeroProducts, "__init__", init)
    monkeypatch.setattr(certifier.Certifier, "check_many", recorded)
    given = tvmmp(state, witnesses=False)
    assert calls == ["entries"]
    with_entries, certificates[:] = list(certificates), []
    init_cert = certifier.Certifier.__init__

    def no_pattern(self, *args, **kwargs):  # type: ignore[no-untyped-def]
        kwargs.pop("pattern", None)
        init_cert(self, *args, **kwargs)

    monkeypatch.setattr(certifier.Certifier, "__init__", no_pattern)
    scanned = tvmmp(state, witnesses=False)
    assert calls == ["entries", "scan"]
    np.testing.assert_array_equal(given.alpha, scanned.alpha)
    assert given.certified == scanned.certified and with_entries == certificates and certificates
