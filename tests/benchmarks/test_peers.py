"""The pycapacity comparison (benchmarks.peers): structure and agreement, no timed assertions."""

from __future__ import annotations

import json

import numpy as np
import pytest

from benchmarks import peers
from benchmarks.notes import peer_notes
from benchmarks.report import peer_rows


def test_fingertip_jacobian_is_the_chain_geometry() -> None:
    """Columns z_i x (p_tip - p_i): each orthogonal to its joint's axis (checked through the
    seeded draw made again here)."""
    jac = peers.fingertip_jacobian(5, seed=3)
    rng = np.random.default_rng(3)
    axes = rng.normal(size=(5, 3))
    axes /= np.linalg.norm(axes, axis=1, keepdims=True)
    assert jac.shape == (3, 5)
    assert np.allclose(np.einsum("ij,ji->i", axes, jac), 0.0, atol=1e-15)
    assert np.all(np.linalg.norm(jac, axis=0) < 6 * 0.06)


def test_report_rows_with_and_without_pycapacity(monkeypatch: pytest.MonkeyPatch) -> None:
    report = json.loads(json.dumps(peers.bench_peers((3, 4), repeats=1, lp_repeats=1)))
    row = report["fingers"]["3"]
    assert row["method"] == "zonotope" and row["vertices"] == 8 and row["lp"]["num_lps"] > 0
    assert row["vs_lp"]["vertices"] == row["vs_lp"]["peer_vertices"] == 8
    assert row["vs_lp"]["hausdorff_rel"] < 1e-9
    assert len(peer_rows({"peers": report})) == 2 * 3 + 2 + 1
    if report["peer_version"] is not None:
        assert row["vs_peer"]["hausdorff_rel"] < 1e-9 and row["vs_peer"]["peer_vertices"] == 8
        assert row["force_vs_peer"]["hausdorff_rel"] < 1e-6
        assert report["met"] in (True, False) and row["tvms"]["ratio"] > 0
    monkeypatch.setattr(peers, "_pycapacity", lambda: None)
    alone = peers.bench_peers((3,), repeats=1, lp_repeats=1)
    assert alone["met"] is None and alone["fingers"]["3"]["tvms"]["peer_s"] is None
    assert alone["fingers"]["3"]["vs_peer"] is None
    assert "pycapacity -" in peer_rows({"peers": alone})[0]
    assert peer_notes({"peers": alone}) == []
    slow = json.loads(json.dumps(report))
    slow["met"] = False
    slow["fingers"]["3"]["tvms"]["ratio"] = 0.5
    assert "3 joints tvms x0.50" in peer_notes({"peers": slow})[0]
