"""Sweeps: the same rows serially, on a process pool and on a local Dask cluster."""

from __future__ import annotations

import pytest

from mjtvm import ParamError, tvmmp
from mjtvm.jobs.sweep import SweepPoint, grid, run_sweep
from mjtvm.lift.states import lift_state
from mjtvm.lift.trajectory import scripted_lift

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
        assert row["certified"] is (not direct.uncertified()) is True
        assert row["z"] == float(lift.z[p.state])


def test_process_pool_gives_the_same_rows(serial):
    assert run_sweep(POINTS, jobs=2, chunk=1, progress=False) == serial


def test_process_pool_with_default_tasks_gives_the_same_rows(serial):
    """Forked workers, several configurations per task (the bench's setting): every field of
    every row equal to the serial run's, to the bit, in the order of the points."""
    assert run_sweep(POINTS, jobs=2, progress=False) == serial


@pytest.mark.parametrize("chunk", [1, 2, 30])
def test_forked_tasks_cover_every_point_once(chunk):
    from mjtvm.jobs.sweep import _fork_tasks, _groups

    points = grid(mus=(0.1, 0.5), states=range(10), num_states=10) + grid(
        hands=("humanlike",), states=(2, 7), num_states=10
    )
    tasks = _fork_tasks(_groups(points, chunk), jobs=2)
    solved = [(key, i) for task in tasks for key, states in task for i in states]
    assert sorted(solved) == sorted(
        ((p.scenario, p.hand, p.num_states, p.variant, p.reading, p.mu, p.mg, p.limit_horizon), p.state)
        for p in points
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
        # by address: the handshake check passes a real scheduler
        assert run_sweep(POINTS[:2], cluster=cluster.scheduler_address, progress=False) == serial[:2]


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
    with pytest.raises(ParamError, match=match):
        SweepPoint(**kwargs)


def test_bad_jobs():
    with pytest.raises(ParamError, match=r"^jobs: "):
        run_sweep(POINTS, jobs=0, progress=False)


def test_pool_and_dask_rows_are_checkpointed(tmp_path):
    seen: list[dict] = []
    rows = run_sweep(POINTS[:4], jobs=2, chunk=1, progress=False, on_rows=seen.extend)
    assert sorted(map(repr, seen)) == sorted(map(repr, rows))


# ------------------------------------------------- faults of parallel sweeps (subprocesses)
def _mjtvm() -> list[str]:
    """The ``mjtvm`` command of this interpreter's environment."""
    import sys
    from pathlib import Path

    script = Path(sys.executable).with_name("mjtvm")
    return [str(script)] if script.exists() else [sys.executable, "-m", "mjtvm.cli"]


def _children(pid: int) -> list[int]:
    """The live (not zombie) child processes of ``pid``, from /proc."""
    import os

    out = []
    for entry in os.listdir("/proc"):
        if entry.isdigit():
            try:
                with open(f"/proc/{entry}/stat", "rb") as f:
                    fields = f.read().rsplit(b")", 1)[1].split()
            except OSError:
                continue
            if int(fields[1]) == pid and fields[0] != b"Z":
                out.append(int(entry))
    return out


def _alive(pid: int) -> bool:
    """Whether ``pid`` runs (a zombie is gone: it only waits to be reaped)."""
    try:
        with open(f"/proc/{pid}/stat", "rb") as f:
            return f.read().rsplit(b")", 1)[1].split()[0] != b"Z"
    except OSError:
        return False


def _wait(condition, timeout: float) -> bool:
    import time

    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if condition():
            return True
        time.sleep(0.05)
    return condition()


# 4800 rows (20 mu x 60 mg x 4 states) in 4 forked tasks of one state each: a task takes
# seconds (about 10 s on one core), the whole sweep tens of seconds on 2 workers.
_LONG = [
    "--mu",
    ",".join(f"{0.05 * k:.2f}" for k in range(1, 21)),
    "--mg",
    ",".join(f"{0.5 + 0.05 * k:.2f}" for k in range(60)),
    "--states",
    "4",
]


@pytest.mark.skipif(not __import__("sys").platform.startswith("linux"), reason="/proc and forked workers")
@pytest.mark.parametrize("how", ["SIGKILL", "SIGTERM"])
def test_a_killed_parallel_sweep_leaves_no_worker_and_no_lock(tmp_path, how):
    """Kill the parent of a --jobs 2 sweep mid-run: its workers end with it (within 5 s), and the
    next run into the folder starts and finishes."""
    import contextlib
    import os
    import signal
    import subprocess

    workers: list[int] = []
    proc = subprocess.Popen(
        [*_mjtvm(), "sweep", *_LONG, "--jobs", "2", "--out", str(tmp_path), "--quiet"],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
    )
    try:
        assert _wait(lambda: len(_children(proc.pid)) >= 2, 60), "the pool did not start"
        workers += _children(proc.pid)
        proc.send_signal(getattr(signal, how))
        proc.wait(timeout=30)
        assert _wait(lambda: not any(_alive(w) for w in workers), 5), "workers outlived the killed sweep"
    finally:
        for w in workers:  # whatever happened: no process of this test outlives it
            with contextlib.suppress(ProcessLookupError):
                os.kill(w, signal.SIGKILL)
        proc.kill()
        proc.wait()
        proc.stderr.close()
    words = ["sweep", "--states", "2", "--out", str(tmp_path), "--quiet"]
    again = subprocess.run([*_mjtvm(), *words], capture_output=True, text=True, timeout=120)
    assert again.returncode == 0, again.stderr
    assert (tmp_path / "sweep.json").exists()


@pytest.mark.skipif(not __import__("sys").platform.startswith("linux"), reason="forked workers")
def test_ctrl_c_stops_a_parallel_sweep_at_once_and_keeps_the_finished_rows(tmp_path):
    """SIGINT to the process group (what a terminal's Ctrl-C does) once a task has finished:
    exit 130 well within 5 s (the workers are not left to finish their tasks), one line on
    stderr, and the checkpoint holds the finished rows."""
    import contextlib
    import json
    import os
    import re
    import signal
    import subprocess
    import threading
    import time

    workers: list[int] = []
    proc = subprocess.Popen(
        [*_mjtvm(), "sweep", *_LONG, "--jobs", "2", "--out", str(tmp_path)],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,
    )
    err: list[str] = []
    moving = threading.Event()

    def read() -> None:
        assert proc.stderr is not None
        while chunk := proc.stderr.read(1):
            err.append(chunk)
            if re.search(r"\|\s*[1-9][0-9]*/[0-9]+ ", "".join(err[-80:])):  # a task is finished
                moving.set()

    reader = threading.Thread(target=read, daemon=True)
    reader.start()
    try:
        assert moving.wait(timeout=180), "".join(err)
        workers += _children(proc.pid)
        start = time.monotonic()
        os.killpg(proc.pid, signal.SIGINT)
        proc.wait(timeout=60)
        stopped = time.monotonic() - start
    finally:
        for w in workers:
            with contextlib.suppress(ProcessLookupError):
                os.kill(w, signal.SIGKILL)
        proc.kill()
        proc.wait()
    reader.join(timeout=10)
    text = "".join(err)
    print(f"Ctrl-C to exit: {stopped:.2f} s")
    assert proc.returncode == 130, text
    assert text.rstrip("\n").splitlines()[-1].endswith("mjtvm: interrupted") and "Traceback" not in text
    assert stopped < 5.0, f"{stopped:.1f} s from Ctrl-C to exit"
    assert _wait(lambda: not any(_alive(w) for w in workers), 5)
    doc = json.loads((tmp_path / "sweep.partial.json").read_text())
    assert doc["schema"] == "mjtvm.sweep-checkpoint/1" and len(doc["rows"]) > 0


class _Server:
    """A TCP server on 127.0.0.1 (an ephemeral port) that is not a Dask scheduler: it accepts
    and then stays silent, or greets every connection with an SSH banner. It stops by itself
    after ``lifetime`` seconds, and at the end of the ``with`` block."""

    def __init__(self, speaks: bool, lifetime: float = 30.0) -> None:
        import socket
        import threading

        self.speaks, self.lifetime = speaks, lifetime
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        self.sock.bind(("127.0.0.1", 0))
        self.sock.listen(8)
        self.sock.settimeout(0.2)
        self.address = f"tcp://127.0.0.1:{self.sock.getsockname()[1]}"
        self.done = threading.Event()
        self.thread = threading.Thread(target=self._serve, daemon=True)

    def _serve(self) -> None:
        import time

        conns = []
        end = time.monotonic() + self.lifetime
        try:
            while not self.done.is_set() and time.monotonic() < end:
                try:
                    conn, _ = self.sock.accept()
                except OSError:  # the accept timeout: look at the clock again
                    continue
                conns.append(conn)
                if self.speaks:
                    conn.sendall(b"SSH-2.0-OpenSSH_9.6 not-dask\r\n" * 4)
        finally:
            for conn in conns:
                conn.close()
            self.sock.close()

    def __enter__(self) -> _Server:
        self.thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self.done.set()
        self.thread.join(timeout=5)


@pytest.mark.parametrize("speaks", [False, True], ids=["silent", "speaks-another-protocol"])
def test_a_cluster_address_that_is_not_a_dask_scheduler_is_one_line_within_the_timeout(
    tmp_path, monkeypatch, capsys, speaks
):
    """A server that stays silent after accepting (Client's own timeout covers the connection
    only), or that answers in another protocol: exit 2 within the timeout (1 s here), one line
    naming --cluster and what was expected, no traceback."""
    import time

    import mjtvm.jobs.sweep
    from mjtvm.cli import main

    monkeypatch.setattr(mjtvm.jobs.sweep, "CONNECT_TIMEOUT_S", 1.0)
    words = ["sweep", "--states", "2", "--out", str(tmp_path), "--quiet"]
    with _Server(speaks) as server:
        start = time.monotonic()
        code = main([*words, "--cluster", server.address])
        took = time.monotonic() - start
    err = capsys.readouterr().err
    print(f"--cluster at a {'speaking' if speaks else 'silent'} server: gave up after {took:.2f} s")
    assert code == 2, err
    assert len(err.splitlines()) == 1 and "Traceback" not in err
    assert err.startswith("error: --cluster: ") and "Dask scheduler at " + server.address in err
    if speaks:
        assert "expected a Dask scheduler" in err and "another protocol" in err
    else:
        assert "within 1 s" in err
    assert took < 5.0  # the lift of --states 2 and the timeout (the parent builds no lift for Dask)
    assert not (tmp_path / "sweep.json").exists()
