"""Contact rules (``contact_rules`` of ``mjtvm.grasp/1``): a few glob patterns type the touching
geoms as the explicit ``contacts`` would, explicit entries override them, the first matching rule
wins, and each way a rule can be wrong is one error naming the field."""

from __future__ import annotations

import json
import tomllib
from pathlib import Path
from typing import Any

import pytest

from mjtvm.cli import main
from mjtvm.formats.state_file import state_to_dict
from mjtvm.grasp.document.document import GraspError, read_grasp_document
from mjtvm.grasp.document.validate import schema_problem
from mjtvm.grasp.resolve.file import load_grasp, shipped_grasps
from tests.support.documents import format_toml

CASE2 = shipped_grasps()["case2"]
TIPS = ("f1_tip", "f2_tip", "f3_tip", "f4_tip")


def _doc(**changes: Any) -> dict[str, Any]:
    """Case 2 (palm D, tips 1 and 3 F, tips 2 and 4 L) with an absolute model path, its
    ``contacts`` removed, and ``changes`` applied (``contacts`` among them to keep some)."""
    doc = tomllib.loads(CASE2.read_text(encoding="utf-8"))
    doc["model"] = str(CASE2.parent / doc["model"])
    del doc["contacts"]
    doc.update(changes)
    return doc


def test_three_rules_give_the_state_of_the_explicit_contacts() -> None:
    rules = [
        {"geom": "f[13]_tip", "type": "F"},
        {"body": "f?_link2", "type": "L"},  # the body of tip 2 and 4 (tips 1 and 3 taken above)
        {"body": "world", "type": "D"},  # the palm is a world geom
    ]
    explicit = state_to_dict(load_grasp("case2").state())
    by_rules = load_grasp(_doc(contact_rules=rules))
    assert state_to_dict(by_rules.state()) == explicit  # the same state, so the same alphas
    assert dict(by_rules.contact_types) == {
        "f1_tip": "F",
        "f3_tip": "F",
        "f2_tip": "L",
        "f4_tip": "L",
        "palm": "D",
    }
    assert [m.labels for m in by_rules.rule_matches] == [
        ("f1_tip", "f3_tip"),
        ("f2_tip", "f4_tip"),
        ("palm",),
    ]


def test_explicit_contacts_override_the_rules_and_the_first_matching_rule_wins() -> None:
    grasp = load_grasp(
        _doc(
            contacts=[{"geom": "f2_tip", "type": "F", "mu": 0.9}],
            contact_rules=[
                {"geom": "f1_*", "type": "L"},
                {"geom": "*tip", "type": "F", "mu": 0.5},
                {"geom": "*", "type": "ignore"},
            ],
        )
    )
    assert dict(grasp.contact_types) == {"f2_tip": "F", "f1_tip": "L", "f3_tip": "F", "f4_tip": "F"}
    assert dict(grasp.mu) == {"f2_tip": 0.9, "f1_tip": 0.3, "f3_tip": 0.5, "f4_tip": 0.5}
    assert grasp.ignored_geoms == ("palm",)
    state = grasp.state()
    assert {c.name: c.type for c in state.contacts} == dict(grasp.contact_types)  # palm dropped


def test_the_contact_report_shows_each_rule_and_what_it_typed() -> None:
    rows = load_grasp(
        _doc(
            contact_rules=[
                {"geom": "f?_tip", "type": "F"},
                {"body": "f1_link*", "type": "L"},  # a finger link: in the model, not touching
                {"geom": "palm", "type": "D"},
            ]
        )
    ).contact_report()
    assert [(r["selection"], r["type"], r["found"]) for r in rows] == [
        ("contact_rules[0] geom 'f?_tip'", "F", list(TIPS)),
        ("contact_rules[1] body 'f1_link*'", "L", []),
        ("contact_rules[2] geom 'palm'", "D", ["palm"]),
    ]
    assert abs(rows[0]["distance"]) < 1e-12 and rows[1]["distance"] is None


@pytest.mark.parametrize(
    ("rules", "field", "message"),
    [
        (
            [{"geom": "f1_tipp", "type": "F"}],
            r"contact_rules\[0\]\.geom",
            r"'f1_tipp' matches no geom of the model that can touch the object \(did you mean 'f1_tip'\?\)",
        ),
        (
            [{"geom": "f?_tip", "type": "F"}, {"geom": "object*", "type": "D"}],
            r"contact_rules\[1\]\.geom",
            "'object\\*' matches no geom of the model that can touch the object",
        ),
    ],
)
def test_a_pattern_matching_nothing_in_the_model_is_an_error(
    rules: list[dict[str, Any]], field: str, message: str
) -> None:
    with pytest.raises(GraspError, match=f"{field}: {message}"):
        load_grasp(_doc(contact_rules=rules))


def test_an_f_rule_needs_a_friction_coefficient() -> None:
    doc = _doc(contact_rules=[{"geom": "palm", "type": "D"}, {"geom": "*", "type": "F"}])
    del doc["mu"]
    with pytest.raises(GraspError, match=r"contact_rules\[1\]\.mu: the F rule geom '\*' needs a friction"):
        load_grasp(doc)


def test_a_touching_geom_no_rule_types_is_refused_by_name() -> None:
    grasp = load_grasp(_doc(contact_rules=[{"geom": "f?_tip", "type": "F"}]))
    with pytest.raises(GraspError, match=r"contacts: geom 'palm' touches the object .* or to contact_rules"):
        grasp.state()


@pytest.mark.parametrize(
    ("rules", "field", "message"),
    [
        ([{"geom": "*", "type": "S"}], r"contact_rules\[0\]\.type", "expected one of F, L, D, ignore"),
        ([{"geom": "*", "body": "*", "type": "F"}], r"contact_rules\[0\]", "expected exactly one of geom"),
        ([{"geom": "*"}], r"contact_rules\[0\]\.type", "required"),
        (
            [{"geom": "*", "type": "ignore", "mu": 0.5}],
            r"contact_rules\[0\]\.mu",
            "an ignore rule types nothing: no mu",
        ),
        ([{"geom": "", "type": "F"}], r"contact_rules\[0\]\.geom", "expected a non-empty string"),
        ([], "contact_rules", "expected a list of 1 to 256 rule tables"),
    ],
)
def test_a_malformed_rule_is_one_error_naming_its_field(
    rules: list[dict[str, Any]], field: str, message: str
) -> None:
    with pytest.raises(GraspError, match=f"{field}: {message}"):
        read_grasp_document(_doc(contact_rules=rules))


def test_a_grasp_needs_contacts_or_contact_rules() -> None:
    assert schema_problem(_doc()) == ("contacts", "required (or contact_rules)")
    with pytest.raises(GraspError, match=r"contacts: required \(or contact_rules\)"):
        read_grasp_document(_doc())


def test_every_link_sticking_is_diagnosed_and_a_rule_frees_it(tmp_path: Path, capsys: Any) -> None:
    """Case 2 with one rule typing every touching geom F: the palm's F-point (a world geom: no
    joint moves it) locks every RVDS vertex, and ``mjtvm solve`` says so; typing the palm D by a
    rule before it frees the lift (alpha > 0), and export-state reports each rule."""
    locked = tmp_path / "locked.toml"
    locked.write_text(format_toml(_doc(contact_rules=[{"geom": "*", "type": "F"}])), encoding="utf-8")
    assert main(["solve", str(locked), "--no-witnesses"]) == 0
    out, err = capsys.readouterr()
    doc = json.loads(out)
    assert doc["tvmmp"] == 0.0
    assert [d["contacts"] for d in doc["diagnosis"]] == [["palm"]] * 4
    assert err.count("is on a body no joint moves") == 4 and len(err.splitlines()) == 4
    freed = tmp_path / "freed.toml"
    rules = [{"geom": "palm", "type": "D"}, {"geom": "*", "type": "F"}]
    freed.write_text(format_toml(_doc(contact_rules=rules)), encoding="utf-8")
    assert main(["solve", str(freed), "--no-witnesses"]) == 0
    out, err = capsys.readouterr()
    assert json.loads(out)["tvmmp"] > 0.0 and "diagnosis" not in json.loads(out) and err == ""
    assert main(["export-state", str(freed)]) == 0
    err = capsys.readouterr().err
    assert (
        "contact_rules[0] geom 'palm' D: palm, contact_rules[1] geom '*' F: f1_tip, f2_tip, f3_tip, f4_tip"
        in err
    )
