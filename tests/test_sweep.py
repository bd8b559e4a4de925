"""Sweeps: the same rows serially, on a process pool and on a local Dask cluster."""

from __future__ import annotations

import pytest

from mjtvm import StateError, tvmmp
from mjtvm.sweep import SweepPoint, grid, run_sweep
from mjtvm.trajectory import lift_state, scripted_lift

POINTS = grid(mus=(0.1, 0.5), mgs=(1.0, 2.0), states=(0, 3), num_states=6) + grid(
    variants=("S",), readings=("literal",), states=(1,), num_states=6
)


@pytest.fixture(scope="module")
def serial():
    return run_sweep(POINTS, progress=False)


def test_rows_follow_the_points_and_match_tvmmp(serial):
    assert len(serial) == len(POINTS) == 9
    lift = scripted_lift(num_states=6)
    for p, row in zip(POINTS, serial):
        assert (row["mu"], row["mg"], row["state"], row["variant"]) == (p.mu, p.mg, p.state, p.variant)
        direct = tvmmp(lift_state(lift, p.state, variant=p.variant, reading=p.reading, mu=p.mu, mg=p.mg))
        assert row["tvmmp"] == direct.tvmmp
        assert row["z"] == float(lift.z[p.state])


def test_process_pool_gives_the_same_rows(serial):
    assert run_sweep(POINTS, jobs=2, chunk=1, progress=False) == serial


def test_dask_local_cluster_gives_the_same_rows(serial):
    import distributed  # the "cluster" extra, part of the "test" extra: never skipped

    with distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
    ) as cluster:
        with distributed.Client(cluster) as client:
            assert run_sweep(POINTS, cluster=client, chunk=1, progress=False) == serial


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"variant": "X"}, "variant"),
        ({"mu": -1.0}, "mu"),
        ({"mg": float("nan")}, "mg"),
        ({"state": 30}, "state"),
    ],
)
def test_bad_points(kwargs, match):
    with pytest.raises(StateError, match=match):
        SweepPoint(**kwargs)


def test_bad_jobs():
    with pytest.raises(StateError, match="jobs"):
        run_sweep(POINTS, jobs=0, progress=False)
