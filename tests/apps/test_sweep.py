"""Sweeps: the same rows serially, on a process pool and on a local Dask cluster."""

from __future__ import annotations

import pytest

from mjtvm import StateError, tvmmp
from mjtvm.apps.sweep import SweepPoint, grid, run_sweep
from mjtvm.sim.trajectory import lift_state, scripted_lift

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


def test_process_pool_with_default_tasks_gives_the_same_rows(serial):
    """Forked workers, several configurations per task (the bench's setting): every field of
    every row equal to the serial run's, to the bit, in the order of the points."""
    assert run_sweep(POINTS, jobs=2, progress=False) == serial


@pytest.mark.parametrize("chunk", [1, 2, 30])
def test_forked_tasks_cover_every_point_once(chunk):
    from mjtvm.apps.sweep import _fork_tasks, _groups

    points = grid(mus=(0.1, 0.5), states=range(10), num_states=10) + grid(
        hands=("humanlike",), states=(2, 7), num_states=10
    )
    tasks = _fork_tasks(_groups(points, chunk), jobs=2)
    solved = [(key, i) for task in tasks for key, states in task for i in states]
    assert sorted(solved) == sorted(
        ((p.scenario, p.hand, p.num_states, p.variant, p.reading, p.mu, p.mg), p.state) for p in points
    )
    for task in tasks:  # one lift per task, at most `chunk` states of it
        assert len({key[:3] for key, _ in task}) == 1
        assert len({i for _, states in task for i in states}) <= chunk


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


def test_resume_after_an_interrupt_computes_only_the_missing_rows(tmp_path, monkeypatch, capsys):
    """A kill simulated by KeyboardInterrupt from the solver after 3 rows: exit 130, a checkpoint
    with the 3 finished rows and no result; --resume then solves the 5 others, and the files
    equal those of an uninterrupted run."""
    import json

    import mjtvm.apps.sweep
    from mjtvm.cli import main

    words = ["sweep", "--mu", "0.1,0.5", "--mg", "1,2", "--states", "3", "--state-indices", "0,2", "--quiet"]
    assert main([*words, "--out", str(tmp_path / "whole")]) == 0
    calls = []

    def counted(state, **kwargs):
        calls.append(1)
        if interrupt_at and len(calls) == interrupt_at:
            raise KeyboardInterrupt
        return tvmmp(state, **kwargs)

    monkeypatch.setattr(mjtvm.apps.sweep, "tvmmp", counted)
    interrupt_at = 4
    out = tmp_path / "cut"
    assert main([*words, "--out", str(out)]) == 130
    assert capsys.readouterr().err == "mjtvm: interrupted\n"
    assert sorted(p.name for p in out.iterdir()) == [".mjtvm.lock", "sweep.partial.json"]
    assert len(json.loads((out / "sweep.partial.json").read_text())["rows"]) == 3
    calls.clear()
    interrupt_at = 0
    assert main([*words, "--out", str(out), "--resume"]) == 0
    assert len(calls) == 8 - 3
    assert sorted(p.name for p in out.iterdir()) == [".mjtvm.lock", "sweep.csv", "sweep.json"]
    for name in ("sweep.json", "sweep.csv"):
        assert (out / name).read_text() == (tmp_path / "whole" / name).read_text()
    calls.clear()  # a finished sweep resumed over a larger grid keeps its rows too
    wider = [w if w != "0,2" else "0,1,2" for w in words]
    assert main([*wider, "--out", str(out), "--resume"]) == 0
    assert len(calls) == 4


def test_pool_and_dask_rows_are_checkpointed(tmp_path):
    seen: list[dict] = []
    rows = run_sweep(POINTS[:4], jobs=2, chunk=1, progress=False, on_rows=seen.extend)
    assert sorted(map(repr, seen)) == sorted(map(repr, rows))
