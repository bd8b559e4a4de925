"""The rerun recording of the lift (mjtvm.viewer.viz, `mjtvm replay --rrd`), read back with rerun's own query API."""

from __future__ import annotations

import csv
from pathlib import Path
from typing import Any

import datafusion  # noqa: F401  # the rerun-sdk[catalog] extra (part of .[test]); read-back needs it
import numpy as np
import pytest
from rerun.server import Server
from scipy.spatial import ConvexHull

from mjtvm.cli import main
from mjtvm.jobs.replay import ReplayOutput, run_replay
from mjtvm.lift.states import lift_state
from mjtvm.polytopes.tvms import tvms
from mjtvm.viewer.viz import Z_UNIT, record_replay

STATES = 4
RUNS = ("L", "S_physical", "S_literal")  # S_physical: no solution at any of the 4 states (README)
FULL = ("L", "S_literal")  # the runs with a solution at every state


def _run(variant: str, reading: str | None) -> str:
    return "L" if variant == "L" else f"S_{reading}"


@pytest.fixture(scope="module")
def replay(tmp_path_factory: pytest.TempPathFactory) -> tuple[ReplayOutput, dict[str, Any]]:
    out = tmp_path_factory.mktemp("viz")
    result = run_replay(
        out=out, num_states=STATES, readings=("physical", "literal"), plots=False, sweeps=False
    )
    info = record_replay(result, out / "lift.rrd", recording_id="lift", tvms_every=1)
    return result, info


def _read(path: Path, index: str) -> Any:
    with Server(host="127.0.0.1", datasets={"lift": [str(path)]}) as server:
        client = server.client()  # kept alive until the query has run
        dataset = client.get_dataset("lift")
        return dataset.reader(index=index).to_pandas()


@pytest.fixture(scope="module")
def frame(replay: tuple[ReplayOutput, dict[str, Any]]) -> Any:
    return _read(replay[0].files["lift.csv"].with_name("lift.rrd"), "state")


def _cell(frame: Any, column: str, i: int) -> Any:
    """The value logged at state ``i`` (``None`` when nothing or only empty batches were logged)."""
    if column not in frame.columns:
        return None
    rows = frame[frame["state"] == i]
    assert len(rows) == 1
    value = rows[column].iloc[0]
    return None if value is None or len(value) == 0 else value


def test_entity_paths_exist(replay: tuple[ReplayOutput, dict[str, Any]], frame: Any) -> None:
    joints = lift_state(replay[0].lift, 0).joint_names
    wanted = [
        "/scene/palm:Boxes3D:half_sizes",
        "/scene/links:Capsules3D:translations",
        "/scene/tips:Ellipsoids3D:centers",
        "/scene/object:Ellipsoids3D:centers",
    ]
    for run in RUNS:
        wanted += [f"/scene/{run}/contacts:Points3D:positions", f"/scene/{run}/contacts:Points3D:labels"]
        wanted += [] if run == "L" else [f"/scene/{run}/slides:Arrows3D:vectors"]
    for run in FULL:
        wanted += [
            f"/scene/{run}/forces:Arrows3D:vectors",
            f"/scene/{run}/distribution:Mesh3D:vertex_positions",
            f"/scene/{run}/distribution:Mesh3D:triangle_indices",
            f"/scene/{run}/tvms:Mesh3D:vertex_positions",
            f"/tvmmp/{run}:Scalars:scalars",
            f"/limiting/{run}:Scalars:scalars",
            *(f"/alpha/{run}/k0_l{l}:Scalars:scalars" for l in range(4)),
        ]
        for j in joints:
            wanted += [
                f"/joints/{j}/range:LineStrips2D:strips",
                f"/joints/{j}/{run}/box:Boxes2D:half_sizes",
                f"/joints/{j}/{run}/witness:Points2D:positions",
            ]
    assert sorted(set(wanted) - set(frame.columns)) == []


def test_one_time_point_per_state_on_both_timelines(
    replay: tuple[ReplayOutput, dict[str, Any]], frame: Any
) -> None:
    assert sorted(frame["state"]) == list(range(STATES))
    lift = replay[0].lift
    by_z = _read(replay[0].files["lift.csv"].with_name("lift.rrd"), "lift_z")
    assert sorted(by_z["lift_z"]) == [round(float(z) / Z_UNIT) for z in lift.z]


def test_tvmmp_alpha_and_limiting_equal_the_csv(
    replay: tuple[ReplayOutput, dict[str, Any]], frame: Any
) -> None:
    with replay[0].files["lift.csv"].open(newline="", encoding="utf-8") as f:
        rows = list(csv.DictReader(f))
    assert {_run(r["variant"], r["reading"]) for r in rows} == set(RUNS)
    assert len(rows) == len(RUNS) * STATES
    for row in rows:
        run, i = _run(row["variant"], row["reading"]), int(row["state"])
        got = _cell(frame, f"/tvmmp/{run}:Scalars:scalars", i)
        assert (None if got is None else float(got[0])) == (
            None if row["tvmmp"] == "" else float(row["tvmmp"])
        )
        for l in range(4):
            got = _cell(frame, f"/alpha/{run}/k0_l{l}:Scalars:scalars", i)
            want = row[f"alpha_k0_l{l}"]
            assert (None if got is None else float(got[0])) == (None if want == "" else float(want))
        got = _cell(frame, f"/limiting/{run}:Scalars:scalars", i)
        want = None if row["limiting_k"] == "" else [float(row["limiting_k"]), float(row["limiting_l"])]
        assert (None if got is None else list(got)) == want


def test_polytope_meshes_have_the_distribution_and_tvms_vertices(
    replay: tuple[ReplayOutput, dict[str, Any]], frame: Any
) -> None:
    out, info = replay
    assert info["tvms_states"] == list(range(STATES))
    for rec in out.records:
        i, run = rec.index, _run(rec.variant, rec.reading)
        dist = [v[:3] for v in rec.result.distribution if v is not None]
        got = _cell(frame, f"/scene/{run}/distribution:Mesh3D:vertex_positions", i)
        if not dist:
            assert got is None
        else:  # the origin and min_k alpha_kl r_l, each a vertex of the pyramid
            want = np.vstack([np.zeros(3), *dist])
            got = np.vstack(got)
            assert len(got) == len(want) == len(ConvexHull(want).vertices)
            assert np.allclose(np.sort(got, axis=0), np.sort(want, axis=0), atol=1e-6)
        state = lift_state(out.lift, i, variant=rec.variant, reading=rec.reading or "physical")  # type: ignore[arg-type]
        result = tvms(state)
        got = _cell(frame, f"/scene/{run}/tvms:Mesh3D:vertex_positions", i)
        if result.status != "bounded":
            assert got is None
        else:  # inside the RVDS cone (pure translations): the mesh holds every vertex of the TVMS
            assert np.allclose(result.vertices[:, 3:], 0.0)
            assert got is not None and len(got) == len(result.vertices) >= 4
            assert np.allclose(
                np.sort(np.vstack(got), axis=0), np.sort(result.vertices[:, :3], axis=0), atol=1e-5
            )


def test_witness_points_show_the_saturated_joints(
    replay: tuple[ReplayOutput, dict[str, Any]], frame: Any
) -> None:
    out = replay[0]
    red = int.from_bytes(bytes([230, 30, 30, 255]), "big")
    for rec in out.records:
        state, res, run = lift_state(out.lift, rec.index), rec.result, _run(rec.variant, rec.reading)
        for j, (name, rng) in enumerate(zip(state.joint_names, state.operation_ranges, strict=True)):
            pos = _cell(frame, f"/joints/{name}/{run}/witness:Points2D:positions", rec.index)
            if res.limiting is None:
                assert pos is None
                continue
            w = res.witnesses[res.limiting[0]][res.limiting[1]]
            assert w is not None
            want = [w.torques[j] / rng.max_torque, -w.speeds[j] / rng.max_speed]
            assert np.allclose(pos[0], want, atol=1e-6)
            color = _cell(frame, f"/joints/{name}/{run}/witness:Points2D:colors", rec.index)
            assert (int(color[0]) == red) == (name in rec.saturated)
    assert any(rec.saturated for rec in out.records)


def test_cli_writes_a_recording(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    rrd = tmp_path / "lift.rrd"
    args = ["replay", "--states", "2", "--contacts", "L", "--no-plots", "--no-sweeps", "--quiet"]
    assert main([*args, "--out", str(tmp_path), "--rrd", str(rrd), "--spawn", "--tvms-every", "0"]) == 0
    captured = capsys.readouterr()
    assert f"wrote {rrd} (" in captured.out
    assert "no viewer spawned" in captured.err
    frame = _read(rrd, "state")
    assert sorted(frame["state"]) == [0, 1]
    assert "/scene/S/contacts:Points3D:positions" not in frame.columns
    tvms_col = "/scene/L/tvms:Mesh3D:vertex_positions"
    assert tvms_col not in frame.columns or all(_cell(frame, tvms_col, i) is None for i in (0, 1))


def test_verify_results_read_back_from_a_recording(tmp_path: Path) -> None:
    """`mjtvm verify --rrd`: per run and state the LP's TVMMP (min alpha_lp), the simulated
    minimum and each direction's ratio, on the same timelines as the replay."""
    from mjtvm.viewer.viz import record_verify

    rows = [
        {
            "run": run,
            "state": i,
            "z": 0.1 + 0.01 * i,
            "l": l,
            "status": "optimal",
            "alpha_lp": 1.0 + i + l,
            "alpha_sim": 0.5 + i + 0.1 * l,
            "ratio": (0.5 + i + 0.1 * l) / (1.0 + i + l),
            "fail_reason": "torque saturated" if l == 0 else "",
        }
        for run in ("L", "S_literal")
        for i in range(3)
        for l in range(2)
    ]
    path = tmp_path / "verify.rrd"
    assert record_verify(rows, path)["runs"] == ["L", "S_literal"]
    frame = _read(path, "state")
    assert len(frame) == 3
    for run in ("L", "S_literal"):
        tvmmp = [float(np.ravel(v)[0]) for v in frame[f"/verify/{run}/tvmmp:Scalars:scalars"]]
        sim = [float(np.ravel(v)[0]) for v in frame[f"/verify/{run}/alpha_sim:Scalars:scalars"]]
        ratio1 = [float(np.ravel(v)[0]) for v in frame[f"/verify/{run}/ratio/l1:Scalars:scalars"]]
        assert tvmmp == pytest.approx([1.0, 2.0, 3.0])
        assert sim == pytest.approx([0.5, 1.5, 2.5])
        assert ratio1 == pytest.approx([(0.6 + i) / (2.0 + i) for i in range(3)])
    assert len(_read(path, "lift_z")) == 3
