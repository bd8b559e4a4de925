"""The light CSC matrix of Problem 2's path (mjtvm.lp.csc) against scipy's."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest
import scipy.sparse as sp

from mjtvm.lp.csc import Csc, as_csc, from_triplets, scipy_matrix


@pytest.mark.parametrize("seed", range(5))
def test_from_triplets_matches_scipy_coo(seed: int) -> None:
    """Random triplets with repeated positions: the same canonical arrays as scipy's COO -> CSC."""
    rng = np.random.default_rng(seed)
    m, n, k = 7, 9, 40
    rows, cols = rng.integers(0, m, k), rng.integers(0, n, k)  # ~half the positions repeat
    vals = rng.normal(size=k)
    got = from_triplets(rows, cols, vals, (m, n))
    want = sp.coo_matrix((vals, (rows, cols)), shape=(m, n)).tocsc()
    want.sum_duplicates()
    np.testing.assert_array_equal(got.indptr, want.indptr)
    np.testing.assert_array_equal(got.indices, want.indices)
    np.testing.assert_allclose(got.data, want.data, rtol=1e-15, atol=0.0)
    np.testing.assert_allclose(got.toarray(), want.toarray(), rtol=1e-15, atol=0.0)
    back = got.to_scipy()
    assert back.has_canonical_format and back.shape == (m, n)
    np.testing.assert_array_equal(back.toarray(), got.toarray())


def test_as_csc_and_empty() -> None:
    dense = np.array([[0.0, 2.0], [3.0, 0.0], [0.0, -1.0]])
    c = as_csc(dense)
    assert c.nnz == 3 and c.shape == (3, 2)
    np.testing.assert_array_equal(c.toarray(), dense)
    assert as_csc(c) is c and scipy_matrix(dense) is dense
    np.testing.assert_array_equal(scipy_matrix(c).toarray(), dense)
    e = from_triplets(np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros(0), (4, 3))
    assert e.nnz == 0 and e.toarray().shape == (4, 3) and list(e.indptr) == [0, 0, 0, 0]


@pytest.mark.parametrize(
    ("arrays", "match"),
    [
        ((np.ones(2), np.array([0, 1], np.int32), np.array([0, 2], np.int32), (2, 2)), "inconsistent"),
        ((np.ones(2), np.array([0, 1], np.int32), np.array([1, 1, 2], np.int32), (2, 2)), "from 0 to nnz"),
        ((np.ones(2), np.array([0, 5], np.int32), np.array([0, 1, 2], np.int32), (2, 2)), "row index"),
    ],
)
def test_csc_refuses_inconsistent_arrays(arrays: tuple, match: str) -> None:  # type: ignore[type-arg]
    with pytest.raises(ValueError, match=match):
        Csc(*arrays)


def test_problem2_path_does_not_import_scipy(tmp_path) -> None:  # type: ignore[no-untyped-def]
    """`mjtvm solve` on a state: Problem 2 through HiGHS needs neither scipy nor scipy.sparse
    (their import is ~0.12 s of the process; module csc)."""
    code = (
        "import sys, io, contextlib, runpy\n"
        "sys.argv = ['mjtvm', 'solve', sys.argv[1]]\n"
        "out = io.StringIO()\n"
        "try:\n"
        "    with contextlib.redirect_stdout(out):\n"
        "        runpy.run_module('mjtvm.cli', run_name='__main__')\n"
        "except SystemExit as e:\n"
        "    assert e.code in (0, None), e.code\n"
        "assert '\"tvmmp\"' in out.getvalue()\n"
        "print(sorted(m for m in sys.modules if m == 'scipy' or m.startswith('scipy.')))\n"
    )
    from benchmarks.dataset import dataset_state
    from mjtvm.formats.state_file import dump_state

    path = tmp_path / "state.json"
    path.write_text(dump_state(dataset_state(0)), encoding="utf-8")
    done = subprocess.run([sys.executable, "-c", code, str(path)], capture_output=True, text=True, check=True)
    assert done.stdout.strip() == "[]", done.stdout
