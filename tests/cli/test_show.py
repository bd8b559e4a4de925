"""``mjtvm show GRASP``: the contact report as a table and as JSON, its warnings, the rerun
recording, and bad input as one line with exit code 2."""

from __future__ import annotations

import json
import subprocess
from pathlib import Path

import numpy as np
import pytest

from mjtvm.cli import main
from tests.cli.test_cli import _console_script
from tests.docs.test_outputs_doc import assert_documented
from tests.grasp.contacts.test_report import _sunk
from tests.support.documents import format_toml


def test_show_allegro_ik_as_a_user_runs_it() -> None:
    proc = subprocess.run(
        [*_console_script(), "show", "allegro-ik"], capture_output=True, text=True, check=False
    )
    assert proc.returncode == 0, proc.stderr
    assert proc.stderr == ""  # placed touching: nothing to warn about
    lines = proc.stdout.splitlines()
    assert lines[0] == "allegro-ik: contact_tolerance 0.1 mm, geoms within 1 mm of the object"
    assert lines[1].split() == [
        "geom",
        "body",
        "object_geom",
        "distance_mm",
        "normal",
        "type",
        "selected",
        "why",
    ]
    rows = [line.split() for line in lines[2:]]
    assert [r[0] for r in rows] == [f"{f}_tip/geom1" for f in ("ff", "mf", "rf", "th")]
    for r in rows:
        assert r[2] == "ball" and abs(float(r[3])) < 1e-5  # mm: the IK's fingertips touch
        assert np.linalg.norm([float(x) for x in r[4:7]]) == pytest.approx(1.0, abs=2e-3)
        assert r[7:] == ["F", "yes", "-"]


def test_show_json_is_documented_and_matches_the_table(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["show", "case2", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert_documented("show", doc)
    for row in doc["contacts"]:
        assert_documented("show-contacts", row)
    selected = [(r["geom"], r["type"]) for r in doc["contacts"] if r["selected"]]
    assert selected == [("palm", "D"), ("f1_tip", "F"), ("f2_tip", "L"), ("f3_tip", "F"), ("f4_tip", "L")]
    assert doc["problem"] is None and doc["warnings"] == [] and doc["within"] == 1e-3


def test_show_reports_penetration_and_what_export_state_refuses(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Case 2 sunk 1.5 mm into its palm: the table is printed, the penetrations are warned about and
    the refusal (1.5 mm > max_penetration 1 mm) is one more warning; exit 0. export-state: exit 2."""
    path = tmp_path / "sunk.toml"
    path.write_text(format_toml(_sunk()), encoding="utf-8")
    assert main(["show", str(path)]) == 0
    out, err = capsys.readouterr()
    assert "palm" in out.splitlines()[2] and "-1.5" in out.splitlines()[2]
    assert err.splitlines() == [
        "mjtvm: warning: 3 contacts are inside the object's geom 'object', by up to 1.5 mm (max_penetration "
        "1 mm): contacts[0] 'palm' 1.5 mm, contacts[1] 'f1_tip' 0.231 mm, contacts[3] 'f3_tip' 0.378 mm",
        f"mjtvm: warning: the grasp's state would be refused: {path}: contacts[0]: geom 'palm' is 1.5 mm inside the "
        "object's geom 'object' > max_penetration 1 mm: move the finger out (or raise max_penetration)",
    ]
    assert main(["export-state", str(path)]) == 2
    (line,) = capsys.readouterr().err.splitlines()
    assert line.startswith(f"error: {path}: contacts[0]: geom 'palm' is 1.5 mm inside")


def test_show_writes_a_rerun_recording(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    import datafusion  # noqa: F401  # rerun's read-back needs the rerun-sdk[catalog] extra
    from rerun.server import Server

    rrd = tmp_path / "grasp.rrd"
    assert main(["show", "gripper3-box", "--rrd", str(rrd)]) == 0
    assert capsys.readouterr().err == f"wrote {rrd}\n"
    with Server(host="127.0.0.1", datasets={"grasp": [str(rrd)]}) as server:
        client = server.client()  # kept alive until the query has run
        frame = client.get_dataset("grasp").reader(index=None).to_pandas()
    labels = list(frame["/grasp/contacts:Points3D:labels"].iloc[0])
    assert [label.split()[:2] for label in labels] == [
        ["table", "D"],
        ["f1_distal/geom1", "F"],
        ["f2_distal/geom1", "F"],
        ["fm_distal/geom1", "L"],
    ]
    assert all(abs(float(label.split()[2])) < 1e-5 and label.endswith(" mm") for label in labels)  # touching
    # the gripper's links are boxes and capsules, the object a box; the two F-points get cones
    for column in (
        "/grasp/normals:Arrows3D:vectors",
        "/grasp/object/box:Boxes3D:half_sizes",
        "/grasp/hand/capsule:Capsules3D:lengths",
        "/grasp/cones/1:Mesh3D:vertex_positions",
        "/grasp/cones/2:Mesh3D:vertex_positions",
    ):
        assert column in frame.columns
    assert not any(c.startswith("/grasp/cones/3") for c in frame.columns)  # L: no cone


def test_show_writes_a_picture_headless(tmp_path: Path) -> None:
    """MuJoCo's renderer with EGL (set by --png when MUJOCO_GL is unset): three views, labelled."""
    from matplotlib.image import imread

    png = tmp_path / "grasp.png"
    proc = subprocess.run(
        [*_console_script(), "show", "case2", "--png", str(png)], capture_output=True, text=True, check=False
    )
    assert proc.returncode == 0, proc.stderr
    assert proc.stderr == f"wrote {png}\n"
    image = imread(png)
    assert image.shape[:2] == (540, 1296)  # 10.8 x 4.5 in at 120 dpi
    for panel in np.split(image[..., :3], 3, axis=1):
        assert float(panel.std()) > 0.05  # a scene, not a blank frame


@pytest.mark.parametrize(
    ("words", "message"),
    [
        (["show", "x.toml"], "error: x.toml: cannot read the grasp file: No such file or directory"),
        (["show"], "error: GRASP: give a grasp file or a shipped grasp name (e.g. case2)"),
        (["show", "case2", "--within", "-1"], "error: --within: expected"),
        (["show", "case2", "--png", "missing/"], "error: --png: expected a file name, got the folder name"),
        (["show", "case2", "--rrd", "missing/"], "error: --rrd: expected a file name, got the folder name"),
    ],
)
def test_show_bad_input_is_one_line_exit_2(words: list[str], message: str) -> None:
    proc = subprocess.run([*_console_script(), *words], capture_output=True, text=True, check=False)
    assert proc.returncode == 2
    (line,) = proc.stderr.splitlines()
    assert line.startswith(message)
    assert proc.stdout == ""
