"""The dataset readers (mjtvm.grasp.document.dataset) and the batch models (mjtvm.grasp.resolve.batch)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from mjtvm.grasp.document.checks import GraspError
from mjtvm.grasp.document.dataset import DatasetGrasp, read_dataset
from mjtvm.grasp.document.document import read_grasp_document
from mjtvm.grasp.resolve.batch import BatchModels, hand_joints
from mjtvm.grasp.resolve.file import load_grasp, shipped_grasps
from mjtvm.problem2.tvmmp import tvmmp

NQ, J = 27, 13  # a model with 27 qpos numbers and 13 hand joints, for the readers alone


def _rows(n: int = 3) -> np.ndarray:
    g = np.zeros((n, 7 + J))
    g[:, 3] = 1.0  # identity root quaternion
    g[:, 7:] = np.arange(J) * 0.01
    return g


def test_npz_layout(tmp_path: Path) -> None:
    path = tmp_path / "d.npz"
    pose = np.tile([0.1, 0.2, 0.3, 1.0 + 5e-7, 0.0, 0.0, 0.0], (3, 1))  # float32-like round-off
    np.savez(path, grasp_qpos=_rows(), obj_pose=pose, obj_scale=np.array([1.0, 0.5, 2.0]))
    got = read_dataset(path, nq=NQ, num_joints=J)
    assert [e.id for e in got] == ["d:0", "d:1", "d:2"]
    assert got[1].obj_scale == 0.5
    assert got[2].obj_pose is not None and got[2].obj_pose[3] == 1.0  # made exactly unit
    assert np.allclose(got[0].joints, np.arange(J) * 0.01)
    assert got[0].qpos is None


def test_npy_array_and_dict_layouts(tmp_path: Path) -> None:
    np.save(tmp_path / "q.npy", np.zeros((2, NQ)))
    with pytest.raises(
        GraspError, match=r"q\.npy: a 2 x 27 array's meaning is not stated: give --dataset-key"
    ):
        read_dataset(tmp_path / "q.npy", nq=NQ, num_joints=J)
    got = read_dataset(tmp_path / "q.npy", nq=NQ, num_joints=J, key="qpos")
    assert got[0].qpos is not None and got[0].root is None and got[1].id == "q:1"
    np.save(tmp_path / "g.npy", _rows(2))
    assert read_dataset(tmp_path / "g.npy", nq=NQ, num_joints=J, key="grasp_qpos")[0].root is not None
    np.save(tmp_path / "one.npy", {"grasp_qpos": _rows(1)[0], "obj_scale": 1.5}, allow_pickle=True)
    (one,) = read_dataset(tmp_path / "one.npy", nq=NQ, num_joints=J)
    assert one.id == "one" and one.obj_scale == 1.5


def test_csv_layout(tmp_path: Path) -> None:
    row = _rows(1)[0]
    header = [f"grasp_qpos_{i}" for i in range(7 + J)] + ["obj_scale", "id"]
    text = ",".join(header) + "\n" + ",".join(map(str, row)) + ",0.8,first\n"
    (tmp_path / "d.csv").write_text(text)
    (got,) = read_dataset(tmp_path / "d.csv", nq=NQ, num_joints=J)
    assert got.id == "first" and got.obj_scale == 0.8 and np.allclose(got.joints, row[7:])


@pytest.mark.parametrize(
    ("arrays", "match"),
    [
        (
            {"grasp_qpos": np.zeros((2, 7 + J + 1))},
            r"d\.npz: grasp 0: grasp_qpos: expected 20 numbers, got 21",
        ),
        ({"qpos": np.zeros((2, NQ - 1))}, r"grasp 0: qpos: expected 27 numbers, got 26"),
        ({"obj_scale": np.ones(2)}, r"grasp 0: grasp_qpos: missing"),
        (
            {"grasp_qpos": _rows(2), "obj_scale": np.array([1.0, -1.0])},
            r"grasp 1: obj_scale: expected a scale factor in \[0.0001, 10000\], got -1",
        ),
        (
            {"grasp_qpos": _rows(2), "obj_pose": np.zeros((2, 7))},
            r"grasp 0: obj_pose: expected a unit quaternion",
        ),
        ({"grasp_qpos": _rows(2), "obj_scale": np.ones(3)}, r"obj_scale: expected 2 rows"),
    ],
)
def test_malformed_npz(tmp_path: Path, arrays: dict[str, np.ndarray], match: str) -> None:
    np.savez(tmp_path / "d.npz", **arrays)
    with pytest.raises(GraspError, match=match):
        read_dataset(tmp_path / "d.npz", nq=NQ, num_joints=J)


def test_nan_names_index_and_field(tmp_path: Path) -> None:
    rows = _rows(4)
    rows[2, 9] = np.nan
    np.savez(tmp_path / "d.npz", grasp_qpos=rows)
    with pytest.raises(
        GraspError, match=r"grasp 2: grasp_qpos: expected finite numbers, got nan at position 9"
    ):
        read_dataset(tmp_path / "d.npz", nq=NQ, num_joints=J)
    (tmp_path / "d.csv").write_text("qpos_0,qpos_1\n0.1,x\n")
    with pytest.raises(GraspError, match=r"grasp 0: qpos_1: expected a number, got 'x'"):
        read_dataset(tmp_path / "d.csv", nq=2, num_joints=J)


# ------------------------------------------------------------------ on a model
def _as_entry(name: str, shift: np.ndarray) -> tuple[DatasetGrasp, BatchModels, float | None]:
    """The shipped grasp's own configuration as a dataset entry (hand root and object moved by
    ``shift``), its batch models and the grasp file's TVMMP."""
    grasp = load_grasp(name)
    doc, path = read_grasp_document(shipped_grasps()[name])
    batch = BatchModels(doc, path)
    names = hand_joints(batch.model(root=True), doc["object"]["body"])
    m, d = grasp.model, grasp.data
    joints = np.array([d.qpos[m.joint(n).qposadr[0]] for n in names])
    palm, ob = m.body("rh_palm").id, m.body(doc["object"]["body"]).id
    root = np.concatenate([d.xpos[palm] + shift, d.xquat[palm]])
    obj = np.concatenate([d.xpos[ob] + shift, d.xquat[ob]])
    entry = DatasetGrasp("x", "d", 0, None, root, joints, obj)
    return entry, batch, tvmmp(grasp.state(), witnesses=False).tvmmp


def test_batch_grasp_reproduces_the_grasp_file_and_is_translation_invariant() -> None:
    # The grasp file's own configuration given as a dataset row gives the file's TVMMP; moving
    # the hand's root and the object together by a translation changes no alpha (the weight and
    # the RVDS are world vectors; nothing in Problem 2 depends on where the grasp stands).
    for shift in (np.zeros(3), np.array([0.3, -0.2, 0.5])):
        entry, batch, expected = _as_entry("shadow_hand_coupled-sphere", shift)
        got = tvmmp(batch.grasp(entry).state(), witnesses=False).tvmmp
        assert expected is not None and got == pytest.approx(expected, rel=1e-9)


def test_object_scale_compiles_once_and_scales_size_and_mass() -> None:
    doc, path = read_grasp_document(shipped_grasps()["shadow_hand-sphere"])
    batch = BatchModels(doc, path)
    m1, m2 = batch.model(scale=1.0), batch.model(scale=1.2)
    assert batch.model(scale=1.2) is m2  # cached
    g1, g2 = m1.geom("ball"), m2.geom("ball")
    assert g2.size[0] == pytest.approx(1.2 * g1.size[0]) and g1.size[0] == pytest.approx(0.025)
    assert m2.body("ball").mass[0] == pytest.approx(0.08 * 1.2**3)  # the same density


def test_a_damaged_file_is_one_line(tmp_path: Path) -> None:
    """A truncated pickled per-grasp .npy and a CSV field beyond the csv module's limit: one
    GraspError naming the file, not a traceback."""
    from mjtvm.grasp.document.checks import GraspError
    from mjtvm.grasp.document.dataset import read_dataset

    whole = tmp_path / "whole.npy"
    np.save(whole, {"grasp_qpos": np.zeros(10)}, allow_pickle=True)
    cut = tmp_path / "cut.npy"
    cut.write_bytes(whole.read_bytes()[:-20])
    with pytest.raises(GraspError, match=r"cut\.npy: cannot read the dataset"):
        read_dataset(cut, nq=10, num_joints=3)
    wide = tmp_path / "wide.csv"
    wide.write_text("grasp_qpos\n" + "1" * 200_000 + "\n", encoding="utf-8")
    with pytest.raises(GraspError, match=r"wide\.csv: cannot read the dataset"):
        read_dataset(wide, nq=10, num_joints=3)
