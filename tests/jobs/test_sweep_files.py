"""The files of ``mjtvm sweep``: resume after an interrupt or an edited grasp, the typed options."""

from __future__ import annotations

import pytest

from mjtvm import ParamError, tvmmp


def test_resume_after_an_interrupt_computes_only_the_missing_rows(tmp_path, monkeypatch, capsys):
    """A kill simulated by KeyboardInterrupt from the solver after 3 rows: exit 130, a checkpoint
    with the 3 finished rows and no result; --resume then solves the 5 others, and the files
    equal those of an uninterrupted run."""
    import json

    import mjtvm.jobs.sweep
    from mjtvm.cli import main

    words = ["sweep", "--mu", "0.1,0.5", "--mg", "1,2", "--states", "3", "--state-indices", "0,2", "--quiet"]
    assert main([*words, "--out", str(tmp_path / "whole")]) == 0
    calls = []

    def counted(state, **kwargs):
        calls.append(1)
        if interrupt_at and len(calls) == interrupt_at:
            raise KeyboardInterrupt
        return tvmmp(state, **kwargs)

    monkeypatch.setattr(mjtvm.jobs.sweep, "tvmmp", counted)
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


def test_resume_recomputes_the_rows_of_an_edited_grasp_file(tmp_path, capsys):
    """Run on a grasp file, edit it (RVDS twice as large: alpha halves) and resume: the rows are
    those of the edited file, said on stderr; the finished rows of the unchanged grasp stay."""
    import json
    import shutil

    from mjtvm.cli import main
    from mjtvm.grasp.resolve.file import shipped_grasps

    shipped = shipped_grasps()["case2"]
    grasp = tmp_path / "mine.toml"
    text = shipped.read_text().replace(
        'model = "four_finger_hand.xml"', f"model = {str(shipped.parent / 'four_finger_hand.xml')!r}"
    )
    grasp.write_text(text)
    words = [
        "sweep",
        "--grasp",
        f"case2,{grasp}",
        "--mu",
        "0.3",
        "--mg",
        "1",
        "--states",
        "3",
        "--state-indices",
        "0,2",
        "--quiet",
    ]
    out = tmp_path / "out"
    assert main([*words, "--out", str(out)]) == 0
    before = json.loads((out / "sweep.json").read_text())
    capsys.readouterr()
    start = text.index("rvds = [")
    rvds = text[start : text.index("\n]\n", start) + 3]  # the RVDS, twice as large: alpha halves
    grasp.write_text(text.replace(rvds, rvds.replace("1.0", "2.0")))
    assert main([*words, "--out", str(out), "--resume"]) == 0
    assert capsys.readouterr().err == "resume: 2 rows recomputed: inputs changed\n"
    after = json.loads((out / "sweep.json").read_text())
    assert main([*words, "--out", str(tmp_path / "fresh")]) == 0
    assert after == json.loads((tmp_path / "fresh" / "sweep.json").read_text())
    mine = [(b, a) for b, a in zip(before, after) if b["scenario"] == str(grasp)]
    assert len(mine) == 2 and all(a["tvmmp"] == pytest.approx(b["tvmmp"] / 2) for b, a in mine)
    assert [a for a in after if a["scenario"] == "case2"] == [b for b in before if b["scenario"] == "case2"]
    shutil.rmtree(tmp_path / "fresh")
    assert main([*words, "--out", str(out), "--resume"]) == 0  # nothing changed since: nothing to say
    assert capsys.readouterr().err == ""


def test_the_cli_hands_the_sweep_typed_options_and_names_its_options_in_errors(tmp_path, monkeypatch, capsys):
    """``mjtvm sweep`` converts its options into a :class:`~mjtvm.jobs.sweep_files.SweepFiles`; a
    :class:`~mjtvm.errors.ParamError` the run raises about a field is reported as its option."""
    import mjtvm.jobs.sweep_files
    from mjtvm.cli import main
    from mjtvm.jobs.sweep_files import SweepFiles

    seen: list[SweepFiles] = []

    def refuse(run, **kwargs):
        seen.append(run)
        raise ParamError(
            "mus", "the grasps have different friction or weight: give the coefficients and the weights"
        )

    monkeypatch.setattr(mjtvm.jobs.sweep_files, "run_sweep_files", refuse)
    words = [
        "sweep",
        "--grasp",
        "case2,case1",
        "--contacts",
        "L,S",
        "--states",
        "5",
        "--state-indices",
        "0,4",
    ]
    assert main([*words, "--out", str(tmp_path), "--quiet"]) == 2
    assert capsys.readouterr().err == (
        "error: --mu: the grasps have different friction or weight: give --mu and --mg (try 'mjtvm sweep --help')\n"
    )
    assert seen == [
        SweepFiles(
            scenarios=("case2", "case1"),
            variants=("L", "S"),
            num_states=5,
            states=(0, 4),
            out=str(tmp_path),
            quiet=True,
        )
    ]
