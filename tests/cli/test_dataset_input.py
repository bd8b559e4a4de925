"""Bad dataset files for ``mjtvm rank``: each is one line on stderr, exit 2, nothing executed."""

from __future__ import annotations

import os
import pickle
import warnings
from pathlib import Path

import numpy as np
import pytest

from mjtvm.cli import main

DATA = Path(__file__).resolve().parents[1] / "data" / "datasets"
GRASP = str(
    Path(__file__).resolve().parents[2] / "models" / "shadow_hand" / "shadow_hand_coupled-sphere.toml"
)


def _good() -> dict[str, np.ndarray]:
    with np.load(DATA / "shadow-sphere.npz") as z:
        return {k: z[k] for k in ("grasp_qpos", "obj_pose", "obj_scale")}


def _refused(tmp_path: Path, capsys: pytest.CaptureFixture[str], dataset: Path, *words: str) -> str:
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a numpy warning would reach stderr
        code = main(
            ["rank", GRASP, str(dataset), *words, "--out", str(tmp_path / "out"), "--quiet", "--no-plots"]
        )
    err = capsys.readouterr().err
    assert code == 2, err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), err
    assert not (tmp_path / "out" / "rank.json").exists()
    return lines[0]


class _Payload:
    """A pickle that, loaded by ``pickle.load``, writes a file."""

    def __init__(self, target: Path, how: str) -> None:
        self.target, self.how = target, how

    def __reduce__(self):  # type: ignore[no-untyped-def]
        if self.how == "system":
            return (os.system, (f"touch {self.target}",))
        if self.how == "open":
            return (open, (str(self.target), "w"))
        return (eval, (f"open({str(self.target)!r}, 'w')",))


@pytest.mark.parametrize("how", ["system", "open", "eval"])
def test_a_pickle_that_would_write_a_file_runs_nothing(tmp_path, capsys, how) -> None:
    target = tmp_path / "written"
    grasp = {"grasp_qpos": _good()["grasp_qpos"][0], "obj_scale": _Payload(target, how)}
    path = tmp_path / "evil.npy"
    np.save(path, np.array(grasp, dtype=object), allow_pickle=True)
    pickle.loads(pickle.dumps(1))  # the payload is real: pickle.load would write the file
    line = _refused(tmp_path, capsys, path)
    assert "evil.npy: cannot read the dataset (the pickle names" in line
    assert "only numpy arrays, numbers, strings and dicts are read" in line
    assert not target.exists()


def test_the_payload_would_write_with_plain_pickle(tmp_path) -> None:
    target = tmp_path / "written"
    pickle.loads(pickle.dumps(_Payload(target, "open")))
    assert target.exists()  # so the test above can fail


def _npz(tmp_path: Path, **changes: object) -> Path:
    arrays = {**_good(), **changes}
    path = tmp_path / "d.npz"
    np.savez(path, **arrays)
    return path


def test_truncated_npz(tmp_path, capsys) -> None:
    path = _npz(tmp_path)
    path.write_bytes(path.read_bytes()[:200])
    assert "d.npz: cannot read the dataset (not a readable .npz (zip) archive" in _refused(
        tmp_path, capsys, path
    )


def test_npy_starting_with_pk_and_a_bad_zip(tmp_path, capsys) -> None:
    npy = tmp_path / "d.npy"
    npy.write_bytes(_npz(tmp_path).read_bytes())
    assert "d.npy: cannot read the dataset (a zip archive (an .npz?), not an .npy file)" in _refused(
        tmp_path, capsys, npy
    )
    bad = tmp_path / "bad.npz"
    bad.write_bytes(b"PK\x03\x04" + b"\x00" * 64)
    assert "bad.npz: cannot read the dataset (not a readable .npz (zip) archive" in _refused(
        tmp_path, capsys, bad
    )


def test_huge_scale(tmp_path, capsys) -> None:
    path = _npz(tmp_path, obj_scale=np.array([1.0, 1e300, 1.0]))
    line = _refused(tmp_path, capsys, path)
    assert line.endswith("d.npz: grasp 1: obj_scale: expected a scale factor in [0.0001, 10000], got 1e+300")


def test_non_unit_quaternion(tmp_path, capsys) -> None:
    pose = _good()["obj_pose"].copy()
    pose[2, 3:] *= 1.001
    line = _refused(tmp_path, capsys, _npz(tmp_path, obj_pose=pose))
    assert "d.npz: grasp 2: obj_pose: expected a unit quaternion" in line and "got norm 1.001" in line


def test_joint_far_outside_its_range(tmp_path, capsys) -> None:
    g = _good()["grasp_qpos"].copy()
    g[1, 10] = 1e6
    line = _refused(tmp_path, capsys, _npz(tmp_path, grasp_qpos=g))
    assert "d.npz: grasp 1: grasp_qpos: joint" in line and "at 1e+06 rad, outside its range" in line
    g[1, 10] = 0.0
    g[1, 7] += 0.5  # within float64, outside the range by far more than the tolerance
    assert "outside its range" in _refused(tmp_path, capsys, _npz(tmp_path, grasp_qpos=g))


@pytest.mark.parametrize(
    ("values", "dtype"),
    [
        (lambda g: g.astype(complex), "complex128"),
        (lambda g: g > 0, "bool"),
        (lambda g: np.zeros(g.shape, dtype="datetime64[s]"), "datetime64[s]"),
        (lambda g: g.astype(int).astype(str), "<U21"),
    ],
)
def test_only_real_numbers(tmp_path, capsys, values, dtype) -> None:
    g = values(_good()["grasp_qpos"])
    line = _refused(tmp_path, capsys, _npz(tmp_path, grasp_qpos=g))
    assert line.endswith(f"d.npz: grasp 0: grasp_qpos: expected real numbers, got {dtype} data")


def test_overflow_to_float64_is_refused_without_a_warning(tmp_path, capsys) -> None:
    g = _good()["grasp_qpos"].astype(np.longdouble)
    g[0, 8] = np.longdouble(10) ** 400
    if not np.isfinite(g[0, 8]):
        pytest.skip("no extended precision here")
    line = _refused(tmp_path, capsys, _npz(tmp_path, grasp_qpos=g))
    assert "d.npz: grasp 0: grasp_qpos: a number beyond float64's range" in line


def test_a_2d_npy_needs_its_meaning_stated(tmp_path, capsys) -> None:
    path = tmp_path / "g.npy"
    np.save(path, _good()["grasp_qpos"])
    line = _refused(tmp_path, capsys, path)
    assert line.endswith(
        "g.npy: a 3 x 20 array's meaning is not stated: give --dataset-key grasp_qpos (root pose + hand joints) or qpos (the model's qpos)"
    )
    # The Shadow's nq is 20 too (13 joints and the ball's free joint): the same rows read as
    # qpos put a palm coordinate on a thumb joint, which its range refuses.
    line = _refused(tmp_path, capsys, path, "--dataset-key", "qpos")
    assert "g.npy: grasp 0: qpos: joint 'rh_THJ3' at 0.793303 rad, outside its range" in line
    out = tmp_path / "ok"
    words = [
        "rank",
        GRASP,
        str(path),
        "--dataset-key",
        "grasp_qpos",
        "--out",
        str(out),
        "--quiet",
        "--no-plots",
    ]
    assert main(words) == 0 and (out / "rank.json").exists()


def test_csv_columns_complete_and_in_order(tmp_path, capsys) -> None:
    text = (DATA / "shadow-sphere.csv").read_text()
    bad = tmp_path / "d.csv"
    bad.write_text(text.replace("grasp_qpos_12,", "grasp_qpos_99,", 1))
    line = _refused(tmp_path, capsys, bad)
    assert line.endswith(
        "d.csv: grasp 0: grasp_qpos_99: expected the column grasp_qpos_12 here (numbered columns complete and in order)"
    )


def test_object_body_missing_from_the_model(tmp_path, capsys) -> None:
    toml = Path(GRASP).read_text().replace('shape = "sphere"\nsize = [0.025]\nmass = 0.08\n', "", 1)
    toml = toml.replace('body = "ball"', 'body = "no_such_body"', 1)
    grasp = tmp_path / "g.toml"
    grasp.write_text(toml.replace('model = "', f'model = "{Path(GRASP).parent}/', 1))
    code = main(
        ["rank", str(grasp), str(DATA / "shadow-sphere.npz"), "--out", str(tmp_path / "o"), "--quiet"]
    )
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and "no_such_body" in err[0]
