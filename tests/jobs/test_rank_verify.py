"""``mjtvm rank --verify``: the simulated columns, the AUC files, --jobs, --resume, bad options."""

from __future__ import annotations

import csv
import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from mjtvm.cli.parser import main
from mjtvm.jobs.rank_row import SIM_FIELDS
from mjtvm.physics.grasp_sim import SIM_COLUMNS

ROOT = Path(__file__).resolve().parents[2]
GRASP = str(ROOT / "models" / "shadow_hand" / "shadow_hand_coupled-sphere.toml")
DATASET = ROOT / "mjtvm" / "data" / "examples" / "shadow-sphere-dataset.npz"


@pytest.fixture(scope="module")
def dataset(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Four grasps of the example: infeasible (0), two evaluated (1, 3), one too deep (last)."""
    z = np.load(DATASET)
    path = tmp_path_factory.mktemp("d") / "d.npz"
    rows = [0, 1, 3, len(z["id"]) - 1]
    np.savez(path, **{k: v[rows] for k, v in z.items()})
    return path


@pytest.fixture(scope="module")
def verified(dataset: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("out")
    words = [
        "rank",
        GRASP,
        str(dataset),
        "--verify",
        "--refuse-penetration",
        "--jobs",
        "2",
        "--out",
        str(out),
    ]
    assert main([*words, "--quiet"]) == 0
    return out


def test_the_rows_gain_the_simulated_columns(verified: Path) -> None:
    assert SIM_FIELDS == SIM_COLUMNS
    rows = {r["id"]: r for r in json.loads((verified / "rank.json").read_text())}
    assert all(list(r)[-len(SIM_FIELDS) - 1 : -1] == list(SIM_FIELDS) for r in rows.values())
    infeasible, good, bad, deep = (rows[f"shadow-sphere-{i}"] for i in ("000", "001", "003", "035-closed"))
    assert (
        infeasible["sim_hold"] is None and infeasible["sim_failure"] == "no optimal pair: no witness to drive"
    )
    assert deep["failure"] == "penetration" and deep["sim_failure"] == "not evaluated: penetration"
    assert deep["sim_hold"] is None and deep["sim_speed_success"] is None
    # the squeeze holds grasp 1 under every push; grasp 3's sphere leaves pushed along -x
    assert good["sim_hold"] is True and good["sim_hold_dirs"] == 6 and good["sim_hold_translation"] < 0.05
    assert bad["sim_hold"] is False and bad["sim_hold_dirs"] == 0
    assert bad["sim_failure"].startswith("hold: the object leaves the thresholds pushed along -x")
    assert good["sim_speed_dirs"] == bad["sim_speed_dirs"] == 4
    # the prediction holds for grasp 1 (every direction at 0.8 alpha, 3 of 4 at alpha, none at 1.2)
    assert good["sim_speed_success"] is True
    assert (good["sim_speed_pass_08"], good["sim_speed_pass_10"], good["sim_speed_pass_12"]) == (
        1.0,
        0.75,
        0.0,
    )
    assert bad["sim_speed_success"] is False and bad["sim_speed_pass_08"] == 0.0
    assert "speed at 0.8 alpha, l = 0: twist magnitude off" in bad["sim_failure"]
    with (verified / "rank.csv").open(newline="") as f:
        header = next(csv.reader(f))
    assert header[-len(SIM_FIELDS) - 1 : -1] == list(SIM_FIELDS)
    import pyarrow.parquet as pq

    table = pq.read_table(verified / "rank.parquet")
    assert table.column_names == header
    assert str(table.schema.field("sim_hold").type) == "bool"
    assert str(table.schema.field("sim_speed_pass_08").type) == "double"


def test_the_auc_files(verified: Path) -> None:
    doc = json.loads((verified / "rank-auc.json").read_text())
    assert doc["schema"] == "mjtvm.rank-auc/1" and doc["resamples"] == 2000
    table = {(r["measure"], r["target"]): r for r in doc["rows"]}
    measures = ["tvmmp", "alpha_l0", "alpha_l1", "alpha_l2", "alpha_l3", "epsilon_l1", "epsilon_linf"]
    assert [m for m, t in table if t == "sim_hold"] == [*measures, "grasp_sigma_min", "force_closure"]
    hold = table["tvmmp", "sim_hold"]
    assert (hold["positives"], hold["negatives"], hold["excluded"]) == (1, 1, 2)
    assert hold["auc"] == 0.0  # grasp 1 holds with TVMMP 0.0486, grasp 3 does not with 0.0508
    speed = table["tvmmp", "sim_speed_success"]
    assert (speed["positives"], speed["negatives"], speed["excluded"]) == (1, 1, 2)
    assert speed["auc"] == 0.0  # grasp 1 passes with TVMMP 0.0486, grasp 3 fails with 0.0508
    assert (verified / "rank-auc.png").read_bytes()[:4] == b"\x89PNG"
    assert (verified / "rank-auc.csv").read_text().startswith("measure,target,auc,ci_low,ci_high,")


def test_resume_keeps_verified_rows_and_refuses_the_other_kind(
    verified: Path, dataset: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    before = (verified / "rank.json").read_text()
    words = ["rank", GRASP, str(dataset), "--refuse-penetration", "--resume", "--no-plots"]
    assert main([*words, "--verify", "--out", str(verified)]) == 0
    assert "resume: 4 of 4 rows already finished" in capsys.readouterr().out
    assert (verified / "rank.json").read_text() == before
    assert main([*words, "--out", str(verified), "--quiet"]) == 2  # a plain run on verified rows
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "are of a run with --verify" in err[0]
    plain = tmp_path / "plain"
    assert main(["rank", GRASP, str(dataset), "--out", str(plain), "--quiet", "--no-plots"]) == 0
    assert "sim_hold" not in json.loads((plain / "rank.json").read_text())[0]
    capsys.readouterr()
    assert main([*words, "--verify", "--out", str(plain), "--quiet"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "are of a run without --verify" in err[0]


def test_resume_digest_follows_the_simulation_protocol(
    dataset: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A verified row holds for the protocol that made it: a changed hold-test threshold or
    step changes the digest ``--resume`` matches; a plain run's digest does not see it."""
    from mjtvm.jobs.rank_inputs import inputs_digest
    from mjtvm.physics import disturb, grasp_sim
    from mjtvm.physics.settings import SimSettings

    verified = inputs_digest(GRASP, [str(dataset)], verify=True)
    plain = inputs_digest(GRASP, [str(dataset)])
    monkeypatch.setattr(disturb, "DISTURB_ANGLE", 20.0)
    assert inputs_digest(GRASP, [str(dataset)], verify=True) != verified
    assert inputs_digest(GRASP, [str(dataset)]) == plain
    monkeypatch.undo()
    assert inputs_digest(GRASP, [str(dataset)], verify=True) == verified
    monkeypatch.setattr(grasp_sim, "HOLD_SETTINGS", SimSettings(timestep=2.5e-4))
    assert inputs_digest(GRASP, [str(dataset)], verify=True) != verified


def test_push_time_without_verify_is_refused(
    dataset: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["rank", GRASP, str(dataset), "--push-time", "0.5", "--out", str(tmp_path), "--quiet"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--push-time" in err[0] and "--verify" in err[0]
    assert main(["rank", GRASP, str(dataset), "--verify", "--push-time", "0", "--out", str(tmp_path)]) == 2
    assert not (tmp_path / "rank.json").exists()


def test_the_simulated_rows_are_the_same_serially_in_a_pool_and_on_dask(
    dataset: Path, verified: Path
) -> None:
    import distributed

    from mjtvm.jobs.rank import rank_rows
    from mjtvm.jobs.rank_inputs import read_datasets

    entries = read_datasets(GRASP, [str(dataset)])
    opts = {"progress": False, "refuse_penetration": True, "verify": True}
    serial = rank_rows(GRASP, entries, **opts)

    def bare(rows: list[dict[str, Any]]) -> dict[str, dict[str, Any]]:
        return {r["id"]: {k: v for k, v in r.items() if k not in ("rank", "inputs")} for r in rows}

    # --jobs 2 (the fixture's run) and one process
    assert bare(serial) == bare(json.loads((verified / "rank.json").read_text()))
    short = rank_rows(GRASP, entries[:2], **opts, hold_time=0.2)
    with (
        distributed.LocalCluster(
            n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
        ) as cluster,
        distributed.Client(cluster) as client,
    ):
        assert rank_rows(GRASP, entries[:2], **opts, hold_time=0.2, cluster=client) == short
