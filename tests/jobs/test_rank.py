"""``mjtvm rank``: the rows, the summary, failures as rows, resume (mjtvm.jobs.rank, rank_files)."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import mjtvm.jobs.rank
from mjtvm.errors import StateError
from mjtvm.grasp.resolve.file import load_grasp
from mjtvm.jobs.rank_files import RankFiles, run_rank_files
from mjtvm.problem2.tvmmp import tvmmp

ROOT = Path(__file__).resolve().parents[2]
GRASP = str(ROOT / "models" / "shadow_hand" / "shadow_hand_coupled-sphere.toml")
DATASET = ROOT / "mjtvm" / "data" / "examples" / "shadow-sphere-dataset.npz"


def _mjtvm() -> list[str]:
    script = Path(sys.executable).with_name("mjtvm")
    return [str(script)] if script.exists() else [sys.executable, "-m", "mjtvm.cli"]


def test_rank_command_on_the_example_dataset(tmp_path: Path) -> None:
    proc = subprocess.run(
        [*_mjtvm(), "rank", GRASP, str(DATASET), "--out", str(tmp_path), "--quiet"],
        capture_output=True,
        text=True,
        check=False,
    )
    assert proc.returncode == 0, proc.stderr
    rows = json.loads((tmp_path / "rank.json").read_text())
    n = len(np.load(DATASET)["id"])
    assert len(rows) == n == 36
    assert (tmp_path / "rank.csv").read_text().count("\n") == n + 1
    for suffix in ("-objects.png", "-tvmmp.png"):
        assert (tmp_path / f"rank{suffix}").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    # The summary's counts are the rows'.
    solved = [r for r in rows if r["failure"] is None]
    positive = [r for r in solved if r["tvmmp"] is not None and r["tvmmp"] > 0]
    assert f"rank: {n} grasps: {len(positive)} with TVMMP > 0" in proc.stderr
    assert "failed: " in proc.stderr and len(positive) >= 10
    # The generator's broken grasps (the last four): the open ones fail with their reason, the
    # closed ones (6.5 mm inside) are evaluated and flagged.
    broken = {r["id"]: r for r in rows if r["id"].endswith(("-open", "-closed"))}
    assert len(broken) == 4
    for r in broken.values():
        if r["id"].endswith("-open"):
            assert r["failure"] == "no contact" and r["reason"] and r["tvmmp"] is None
        else:
            assert r["failure"] is None and r["penetration_exceeded"] is True
            assert r["penetration"] == pytest.approx(6.5e-3, abs=1e-4)
    assert all(r["contacts"] == 3 for r in solved)
    # An infeasible grasp says why: the diagnosis of its pair.
    for r in solved:
        if r["tvmmp"] is None:
            assert r["reason"].startswith("pair [") and not r["feasible"]


def test_a_row_is_the_grasp_files_tvmmp_at_that_configuration(tmp_path: Path) -> None:
    # Row 1 of the example, rebuilt as a grasp file (its joint values, palm pose, sphere pose
    # and radius) and solved by load_grasp: the same TVMMP as the row.
    z = np.load(DATASET)
    rows = mjtvm.jobs.rank.rank_rows(GRASP, _entries()[1:2], progress=False)
    g = z["grasp_qpos"][1]
    from mjtvm.grasp.resolve.batch import hand_joints

    base = load_grasp(GRASP)
    names = hand_joints(base.model, "ball")
    s = float(z["obj_scale"][1])
    doc: dict[str, Any] = {
        "schema": "mjtvm.grasp/1",
        "model": str(ROOT / "models" / "shadow_hand" / "shadow_right_3f_coupled.xml"),
        "mu": 0.6,
        "rvds": [list(map(float, r)) for r in base.rvds],
        "object": {
            "body": "ball",
            "shape": "sphere",
            "size": [0.025 * s],
            "mass": 0.08 * s**3,
            "position": [float(x) for x in z["obj_pose"][1][:3]],
        },
        "configuration": {"qpos": {n: float(v) for n, v in zip(names, g[7:], strict=True)}},
        "contacts": [{"geom": n, "type": "F"} for n in ("ff_distal", "mf_distal", "th_distal")],
        "ranges": {"rh_A_*": {"actuator": True, "speed_limit": 2.0}},
    }
    assert np.allclose(
        g[:7],
        [*base.data.xpos[base.model.body("rh_palm").id], *base.data.xquat[base.model.body("rh_palm").id]],
    )
    state = load_grasp(doc).state()
    expected = tvmmp(state, witnesses=False).tvmmp
    assert expected is not None and rows[0]["tvmmp"] == pytest.approx(expected, rel=1e-9)
    # The classic measures of the row are those of the same state.
    from mjtvm.jobs.rank import CLASSIC_COLUMNS
    from mjtvm.measures import classic_measures

    measures = classic_measures(state, polytope=False).to_dict()
    assert rows[0]["force_closure"] is True
    for key in CLASSIC_COLUMNS:
        assert rows[0][key] == pytest.approx(measures[key], rel=1e-9), key


def _entries() -> list[Any]:
    from mjtvm.jobs.rank_inputs import read_datasets

    return read_datasets(GRASP, [str(DATASET)])


def test_interrupted_and_resumed_is_identical(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    whole = RankFiles(grasp=GRASP, datasets=(str(DATASET),), out=tmp_path / "whole", quiet=True)
    run_rank_files(whole, notice=lambda _: None)
    calls = {"n": 0}
    real = mjtvm.jobs.rank.rank_row

    def interrupted(batch: Any, entry: Any, **options: Any) -> dict[str, Any]:
        calls["n"] += 1
        if calls["n"] > 15:
            raise KeyboardInterrupt
        return real(batch, entry, **options)

    monkeypatch.setattr(mjtvm.jobs.rank, "rank_row", interrupted)
    part = RankFiles(grasp=GRASP, datasets=(str(DATASET),), out=tmp_path / "part", quiet=True)
    with pytest.raises(KeyboardInterrupt):
        run_rank_files(part, notice=lambda _: None)
    log = tmp_path / "part" / "rank.partial.jsonl"
    head, *saved = [json.loads(line) for line in log.read_text().splitlines()]
    assert head == {"schema": "mjtvm.rank-checkpoint/2"} and len(saved) == 15
    # A kill in the middle of a line: the torn row is dropped and evaluated again.
    log.write_bytes(log.read_bytes() + b'{"id": "shadow-sphere-0')
    monkeypatch.setattr(mjtvm.jobs.rank, "rank_row", real)
    calls["n"] = 0
    resumed = RankFiles(grasp=GRASP, datasets=(str(DATASET),), out=tmp_path / "part", quiet=True, resume=True)
    run_rank_files(resumed, notice=lambda _: None)
    for name in ("rank.json", "rank.csv", "rank.parquet", "rank-objects.csv"):
        assert (tmp_path / "part" / name).read_bytes() == (tmp_path / "whole" / name).read_bytes(), name
    assert not log.exists()


def test_resume_reads_an_older_checkpoint_and_the_earlier_json(tmp_path: Path) -> None:
    # The rows of an older version's NAME.partial.json (schema 1) and of an earlier NAME.json
    # are kept when their inputs are unchanged: nothing is evaluated again.
    whole = RankFiles(grasp=GRASP, datasets=(str(DATASET),), out=tmp_path, quiet=True)
    run_rank_files(whole, notice=lambda _: None)
    first = {p: p.read_bytes() for p in tmp_path.iterdir()}
    rows = json.loads((tmp_path / "rank.json").read_text())
    (tmp_path / "rank.partial.json").write_text(
        json.dumps({"schema": "mjtvm.rank-checkpoint/1", "rows": rows[:10]})
    )
    (tmp_path / "rank.json").write_text(json.dumps(rows[10:], indent=1))
    said: list[str] = []
    again = RankFiles(grasp=GRASP, datasets=(str(DATASET),), out=tmp_path, quiet=False, resume=True)
    import mjtvm.jobs.rank as rank

    real, rank.rank_row = rank.rank_row, None  # type: ignore[assignment]
    try:
        run_rank_files(again, emit=said.append, notice=lambda _: None)
    finally:
        rank.rank_row = real
    assert "resume: 36 of 36 rows already finished" in said
    assert {p: p.read_bytes() for p in tmp_path.iterdir()} == first


def test_json_list_rows_reads_a_list_in_small_blocks(tmp_path: Path) -> None:
    from mjtvm.jobs.rank_tables import json_list_rows, rows_json_chunks

    rows = [{"id": f"g{i}", "x": [i, {"y": "]},["}], "z": None} for i in range(7)]
    path = tmp_path / "r.json"
    path.write_text("".join(rows_json_chunks(rows)))
    for block in (1, 3, 64, 1 << 20):
        assert list(json_list_rows(path, block=block)) == rows
    path.write_text("[]\n")
    assert list(json_list_rows(path)) == []
    for bad, why in (
        ("{}", "not a JSON list"),
        ('[{"id": 1}', "ends early"),
        ('[{"id": 1} {"id": 2}]', "','"),
        ("[1]", "not a row"),
    ):
        path.write_text(bad)
        with pytest.raises(StateError, match=why):
            list(json_list_rows(path, block=2))


def test_malformed_dataset_is_one_line_and_exit_2(tmp_path: Path) -> None:
    z = dict(np.load(DATASET))
    z["grasp_qpos"] = z["grasp_qpos"].copy()
    z["grasp_qpos"][5, 10] = np.nan
    bad = tmp_path / "bad.npz"
    np.savez(bad, **z)
    proc = subprocess.run(
        [*_mjtvm(), "rank", GRASP, str(bad), "--out", str(tmp_path / "o"), "--quiet"],
        capture_output=True,
        text=True,
        check=False,
    )
    assert proc.returncode == 2
    assert proc.stderr.strip().splitlines() == [
        f"error: {bad}: grasp 5: grasp_qpos: expected finite numbers, got nan at position 10"
    ]


_ORB = """<mujoco model="orb">
  <worldbody>
    <body name="orb"><freejoint/><geom name="orb" type="sphere" size="0.025" mass="0.08"/></body>
  </worldbody>
</mujoco>
"""


def test_object_file_per_grasp_and_two_processes(tmp_path: Path) -> None:
    # The same sphere given as an object file (obj_path, relative to the dataset) in place of
    # the grasp file's: every alpha the same; two local processes give the rows of one.
    (tmp_path / "orb.xml").write_text(_ORB)
    z = {k: v[:6] for k, v in np.load(DATASET).items()}
    np.savez(tmp_path / "a.npz", **z)
    np.savez(tmp_path / "b.npz", **z, obj_path=np.array(["orb.xml"] * 6))
    from mjtvm.jobs.rank_inputs import read_datasets

    a = mjtvm.jobs.rank.rank_rows(GRASP, read_datasets(GRASP, [str(tmp_path / "a.npz")]), progress=False)
    b = mjtvm.jobs.rank.rank_rows(GRASP, read_datasets(GRASP, [str(tmp_path / "b.npz")]), progress=False)
    assert [r["object"] for r in b] == ["orb"] * 6 and [r["object"] for r in a] == ["ball"] * 6
    assert [r["alpha"] for r in a] == [r["alpha"] for r in b]
    assert sum(r["tvmmp"] is not None for r in a) >= 3
    two = mjtvm.jobs.rank.rank_rows(
        GRASP, read_datasets(GRASP, [str(tmp_path / "a.npz")]), jobs=2, progress=False
    )
    assert two == a


def test_pool_tasks_shrink_to_single_grasps_at_the_end(monkeypatch: pytest.MonkeyPatch) -> None:
    # Guided self-scheduling: the tasks keep every grasp once and in order, none larger than
    # ceil(total / (8 jobs)) (a finished grasp reaches the checkpoint soon), and the last ones
    # are single grasps so that the two workers end within about a grasp of each other.
    from mjtvm.jobs.rank_inputs import read_datasets

    entries = read_datasets(GRASP, [str(DATASET)]) * 4  # 144 grasps
    sizes: list[int] = []
    order: list[str] = []

    def record(grasp: str, tasks: Any, jobs: int, finished: Any, opts: Any = ()) -> None:
        for task in tasks:
            sizes.append(len(task))
            order.extend(e.id for e in task)

    monkeypatch.setattr(mjtvm.jobs.rank, "_run_pool", record)
    mjtvm.jobs.rank.stream_rows(GRASP, entries, lambda rows: None, total=len(entries), jobs=2, progress=False)
    assert order == [e.id for e in entries]
    assert max(sizes) == 9 == sizes[0]  # ceil(144 / 16)
    assert sizes == sorted(sizes, reverse=True) and sizes[-4:] == [1, 1, 1, 1]
    # each task at most a quarter of a worker's share of what is left
    left = len(entries)
    for n in sizes:
        assert n <= max(1, -(-left // 8))
        left -= n


def test_generated_mesh_objects_rank_end_to_end(tmp_path: Path) -> None:
    # The generator's mesh mode (two convex pieces per object, one object file per grasp):
    # every grasp it closes by IK is evaluated with its three fingertip contacts on the mesh,
    # the broken ones fail with their reason.
    import importlib.util

    spec = importlib.util.spec_from_file_location(
        "make_rank_dataset", ROOT / "tools" / "make_rank_dataset.py"
    )
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    arrays = module.make(8, 2, 5, mesh=2, folder=tmp_path / "d-objects")
    np.savez(tmp_path / "d.npz", **arrays)
    from mjtvm.jobs.rank_inputs import read_datasets

    rows = mjtvm.jobs.rank.rank_rows(GRASP, read_datasets(GRASP, [str(tmp_path / "d.npz")]), progress=False)
    assert {r["object"] for r in rows} == {"ellipsoid0", "ellipsoid1"}
    good, bad = rows[:6], rows[6:]
    assert all(r["failure"] is None and r["contacts"] == 3 and r["penetration"] < 1e-4 for r in good)
    # The closed one: on the coupled hand (J1 = J2) the first finger's middle link reaches the
    # mesh 3.75 mm deep before its tip does, a touching geom no contact selects ("grasp").
    assert [r["failure"] for r in bad] == ["no contact", "grasp"]
    assert "geom 'ff_middle' touches the object" in bad[1]["reason"]
    assert any(r["tvmmp"] for r in good)


def _generator() -> Any:
    from tests.support.tools import tool_module

    return tool_module("make_rank_dataset")


def test_generator_follows_the_five_finger_grasp_file(tmp_path: Path) -> None:
    # --grasp: the five-finger hand's 22 joints, its four J1 = J2 equalities kept by the IK,
    # every grasp ranked feasible with its five fingertip contacts and 36 LPs.
    grasp = ROOT / "models" / "shadow_hand" / "shadow_hand_5f_coupled-sphere.toml"
    module = _generator()
    assert len(module.coupled_joints(str(grasp.with_name("shadow_right_coupled.xml")))) == 4
    arrays = module.make(3, 0, 7, grasp_file=grasp)
    assert arrays["grasp_qpos"].shape == (3, 7 + 22)
    assert list(arrays["id"]) == [f"shadow_hand_5f_coupled-sphere-{i:03d}" for i in range(3)]
    np.savez(tmp_path / "d.npz", **arrays)
    from mjtvm.jobs.rank_inputs import read_datasets

    rows = mjtvm.jobs.rank.rank_rows(
        str(grasp), read_datasets(str(grasp), [str(tmp_path / "d.npz")]), measures="none", progress=False
    )
    assert all(r["failure"] is None and r["contacts"] == 5 and r["feasible"] for r in rows)
    assert all(np.shape(r["alpha"]) == (6, 6) for r in rows)


@pytest.mark.parametrize(
    ("grasp", "radius", "tips", "tip_radius"),
    [  # the sphere's radius in the model; the fingertips and their radius (m)
        ("allegro/allegro-sphere.toml", 0.035, ("ff_tip", "mf_tip", "rf_tip", "th_tip"), 0.012),
        ("leap_hand/leap_hand-sphere.toml", 0.04, ("if_tip", "mf_tip", "rf_tip", "th_tip"), 0.011),
    ],
)
def test_generator_closes_a_model_sphere_by_ik(
    grasp: str, radius: float, tips: tuple[str, ...], tip_radius: float
) -> None:
    # A file whose sphere is a body of its model (keyframe configuration): each grasp's sphere
    # is the model's scaled by obj_scale, and the IK puts every fingertip on it: the distance
    # from the sphere's centre to the tip geom's centre segment (a point for the Allegro's
    # spheres) is r s + the tip's radius, within the file's contact tolerance (0.1 mm).
    import mujoco

    from mjtvm.grasp.resolve.batch import BatchModels, hand_joints

    path = ROOT / "models" / grasp
    arrays = _generator().make(3, 0, 11, grasp_file=path)
    assert arrays["grasp_qpos"].shape == (3, 7 + 16)
    assert list(arrays["id"]) == [f"{path.stem.split('-')[0]}-sphere-{i:03d}" for i in range(3)]
    batch = BatchModels.from_file(path)
    for qpos, pose, scale in zip(arrays["grasp_qpos"], arrays["obj_pose"], arrays["obj_scale"], strict=True):
        assert 0.9 <= scale <= 1.1
        model = batch.model(None, float(scale))
        data = mujoco.MjData(model)
        for name, value in zip(hand_joints(model, "object"), qpos[7:], strict=True):
            data.qpos[model.joint(name).qposadr[0]] = value
        adr = model.joint("object").qposadr[0]
        data.qpos[adr : adr + 7] = pose
        mujoco.mj_kinematics(model, data)
        assert model.geom_size[model.geom("object").id][0] == pytest.approx(radius * scale, rel=1e-12)
        for tip in tips:
            body = model.body(tip).id
            geom = next(
                g for g in range(model.ngeom) if model.geom_bodyid[g] == body and model.geom_contype[g]
            )
            capsule = model.geom_type[geom] == mujoco.mjtGeom.mjGEOM_CAPSULE
            half = float(model.geom_size[geom][1]) if capsule else 0.0
            centre, axis = data.geom_xpos[geom], data.geom_xmat[geom].reshape(3, 3)[:, 2]
            d = pose[:3] - centre
            t = float(np.clip(d @ axis, -half, half))  # the segment's point nearest the centre
            gap = float(np.linalg.norm(d - t * axis)) - radius * scale - tip_radius
            assert abs(gap) < 1e-4, (tip, gap)


def test_qpos_layout_gives_the_rows_of_grasp_qpos(tmp_path: Path) -> None:
    # The same grasps as the model's whole qpos (N x nq: the hand's joints and the object's
    # free joint; the palm is fixed, so its pose is the model's, as in the example): the same rows.
    from mjtvm.jobs.rank_inputs import read_datasets

    z = {k: v[:5] for k, v in np.load(DATASET).items()}
    batch = mjtvm.jobs.rank.batch_models(GRASP)
    model = batch.model()
    from mjtvm.grasp.resolve.batch import hand_joints

    names = hand_joints(model, "ball")
    qpos = np.zeros((5, model.nq))
    for i in range(5):
        for n, v in zip(names, z["grasp_qpos"][i][7:], strict=True):
            qpos[i, model.joint(n).qposadr[0]] = v
        adr = model.joint("ball").qposadr[0]
        qpos[i, adr : adr + 7] = z["obj_pose"][i]
    np.savez(tmp_path / "q.npz", qpos=qpos, obj_scale=z["obj_scale"], id=z["id"])
    np.savez(tmp_path / "g.npz", **z)
    a = mjtvm.jobs.rank.rank_rows(GRASP, read_datasets(GRASP, [str(tmp_path / "g.npz")]), progress=False)
    b = mjtvm.jobs.rank.rank_rows(GRASP, read_datasets(GRASP, [str(tmp_path / "q.npz")]), progress=False)
    assert [r["alpha"] for r in a] == [r["alpha"] for r in b]
    assert sum(r["tvmmp"] is not None for r in a) >= 3


def test_dask_gives_the_same_rows(tmp_path: Path) -> None:
    # A local cluster of two worker processes (the "cluster" extra, part of the "test"
    # extra: never skipped): the rows of one process, and the same files.
    import distributed

    entries = _entries()[:12]
    serial = mjtvm.jobs.rank.rank_rows(GRASP, entries, progress=False)
    z = {k: v[:12] for k, v in np.load(DATASET).items()}
    np.savez(tmp_path / "d.npz", **z)
    one = RankFiles(grasp=GRASP, datasets=(str(tmp_path / "d.npz"),), out=tmp_path / "one", quiet=True)
    run_rank_files(one, notice=lambda _: None)
    with (
        distributed.LocalCluster(
            n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
        ) as cluster,
        distributed.Client(cluster) as client,
    ):
        assert mjtvm.jobs.rank.rank_rows(GRASP, entries, cluster=client, progress=False) == serial
        many = RankFiles(
            grasp=GRASP,
            datasets=(str(tmp_path / "d.npz"),),
            out=tmp_path / "many",
            quiet=True,
            cluster=cluster.scheduler_address,
        )
        run_rank_files(many, notice=lambda _: None)
    for name in ("rank.json", "rank.csv", "rank.parquet", "rank-objects.csv"):
        assert (tmp_path / "many" / name).read_bytes() == (tmp_path / "one" / name).read_bytes(), name


def test_grasp_file_without_rvds_is_refused_up_front(tmp_path: Path) -> None:
    import tomllib

    from tests.support.documents import format_toml

    doc = tomllib.loads(Path(GRASP).read_text())
    del doc["rvds"]
    doc["model"] = str(Path(GRASP).parent / doc["model"])
    grasp = tmp_path / "g.toml"
    grasp.write_text(format_toml(doc))
    proc = subprocess.run(
        [*_mjtvm(), "rank", str(grasp), str(DATASET), "--out", str(tmp_path / "o"), "--quiet"],
        capture_output=True,
        text=True,
        check=False,
    )
    assert proc.returncode == 2
    assert proc.stderr.strip().splitlines() == [
        f"error: {grasp}: rvds: mjtvm rank solves Problem 2 (TVMMP): give the RVDS vertices"
    ]


def test_contact_rules_type_each_grasps_own_contacts(tmp_path: Path) -> None:
    # With contact_rules instead of named contacts, each grasp's touching geoms are typed by
    # the rule: the evaluated grasps get the alphas of the named F contacts, and the grasp with
    # its first finger opened (a failure with named contacts) is evaluated on the two left.
    import tomllib

    from tests.support.documents import format_toml

    doc = tomllib.loads(Path(GRASP).read_text())
    del doc["contacts"]
    doc["contact_rules"] = [{"body": "*distal*", "type": "F"}]
    doc["model"] = str(Path(GRASP).parent / doc["model"])
    grasp = tmp_path / "rules.toml"
    grasp.write_text(format_toml(doc))
    z = np.load(DATASET)
    keep = [1, 2, 3, len(z["id"]) - 4]  # three evaluated, one "-open"
    np.savez(tmp_path / "d.npz", **{k: v[keep] for k, v in z.items()})
    from mjtvm.jobs.rank_inputs import read_datasets

    named = mjtvm.jobs.rank.rank_rows(GRASP, read_datasets(GRASP, [str(tmp_path / "d.npz")]), progress=False)
    ruled = mjtvm.jobs.rank.rank_rows(
        str(grasp), read_datasets(str(grasp), [str(tmp_path / "d.npz")]), progress=False
    )
    assert [r["alpha"] for r in ruled[:3]] == [r["alpha"] for r in named[:3]]
    assert named[3]["failure"] == "no contact" and ruled[3]["id"].endswith("-open")
    assert ruled[3]["failure"] is None and ruled[3]["contacts"] == 2
