r"""The paper's grasp scenarios (section 5, Cases 1 and 2): the sources of their grasp files.

A scenario is a JSON document (``mjtvm/data/scenarios/<name>.json``, schema
``mjtvm.scenario/1``): the object (centre, radius, weight mg), the friction coefficient,
the fingers whose joints make the state, the paper's contact points with how each finger
geom reaches it, contact types by geom name, slide directions of S-points, REFS, RVDS,
geoms whose contacts are modelling artefacts (``ignored_geoms``), and per model variant
(``default``: [yaw, pitch] + [pitch, yaw] fingers; ``humanlike``: yaw + three pitches) the
finger joints, the IK start and bounds, and the ``solution`` written by
``tools/make_scenarios.py`` (`make_documents()`): joint angles, IK residuals and the
achieved contacts. From each variant's solution [`grasp_document()`][mjtvm.paper_hand.scenario.grasp_document] writes the grasp
file ``models/paper_hand/<name>[-humanlike].toml`` (``mjtvm.grasp/1``): the paper's
cases are loaded like any grasp ([`load_scenario()`][mjtvm.paper_hand.scenario.load_scenario] is
[`load_grasp()`][mjtvm.grasp.resolve.file.load_grasp] of that file, with ``mg`` and ``mu`` options); the
IK runs only in the generator.

The IK that places the contacts is `mjtvm.paper_hand.placement`.

World frame, SI units.
"""

from __future__ import annotations

import copy
import json
from collections.abc import Mapping
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np

from mjtvm.errors import ModelError
from mjtvm.formats.state_file import state_to_dict
from mjtvm.grasp.resolve.file import load_grasp
from mjtvm.grasp.resolve.loaded import Grasp
from mjtvm.grasp.resolve.variants import VARIANT_GRASPS, grasp_file_name
from mjtvm.paper_hand.hand import finger_joint_names

__all__ = [
    "SCENARIOS",
    "SCHEMA",
    "grasp_document",
    "load_scenario",
    "read_scenario",
    "scenario_document",
    "scenario_path",
    "scenario_variant",
]

SCHEMA = "mjtvm.scenario/1"
SCENARIOS = VARIANT_GRASPS  # the paper's cases: the grasps with both hands
_REQUIRED = (
    "schema",
    "name",
    "object_body",
    "object_position",
    "object_radius",
    "mg",
    "mu",
    "fingers",
    "contact_types",
    "slide_directions",
    "ignored_geoms",
    "refs",
    "rvds",
    "contacts",
    "variants",
)


def scenario_path(name: str) -> Path:
    """Path of the shipped scenario ``name`` (one of `SCENARIOS`)."""
    if name not in SCENARIOS:
        raise ModelError(f"scenario {name!r}", f"unknown (shipped: {', '.join(SCENARIOS)})")
    return Path(str(resources.files("mjtvm.data").joinpath("scenarios").joinpath(f"{name}.json")))


def read_scenario(source: str | Path | Mapping[str, Any]) -> dict[str, Any]:
    """The scenario document of a shipped name, a JSON file path or a mapping (copied)."""
    if isinstance(source, Mapping):
        doc: Any = copy.deepcopy(dict(source))
    else:
        path = Path(source) if isinstance(source, Path) or str(source).endswith(".json") else None
        path = path or scenario_path(str(source))
        try:
            doc = json.loads(path.read_text(encoding="utf-8"))
        except (OSError, json.JSONDecodeError) as e:
            raise ModelError(f"scenario file {str(path)!r}", f"cannot be read: {e}") from e
    if not isinstance(doc, dict) or doc.get("schema") != SCHEMA:
        raise ModelError("scenario", f"expected a JSON object with schema {SCHEMA!r}")
    missing = [k for k in _REQUIRED if k not in doc]
    if missing:
        raise ModelError(f"scenario {doc.get('name')!r}", f"missing keys: {', '.join(missing)}")
    return doc


def scenario_variant(doc: Mapping[str, Any], variant: str) -> Mapping[str, Any]:
    """One variant of a scenario document (``doc["variants"][variant]``).

    Parameters
    ----------
    doc
        A scenario document (`read_scenario()`).
    variant
        The variant's name, e.g. ``"default"``.

    Returns
    -------
    Mapping
        The variant's table.

    Raises
    ------
    ModelError
        The scenario has no such variant (naming those it has).
    """
    if variant not in doc["variants"]:
        raise ModelError(
            f"scenario {doc['name']!r}", f"no variant {variant!r} (has: {', '.join(doc['variants'])})"
        )
    v: Mapping[str, Any] = doc["variants"][variant]
    return v


def load_scenario(
    source: str | Path | Mapping[str, Any],
    *,
    variant: str = "default",
    mg: float | None = None,
    mu: float | Mapping[str, float] | None = None,
    friction_margin: float | None = None,
) -> Grasp:
    r"""A paper case as a [`Grasp`][mjtvm.grasp.resolve.loaded.Grasp]: its shipped grasp file.

    Parameters
    ----------
    source
        A shipped scenario name (`SCENARIOS`; the grasp file
        [`grasp_file_name()`][mjtvm.grasp.resolve.variants.grasp_file_name] of ``variant`` in ``models/paper_hand/``), or any grasp
        file or shipped grasp name (then ``variant`` must stay ``"default"``).
    variant
        Hand of a shipped scenario: ``"default"`` or ``"humanlike"``.
    mg, mu, friction_margin
        Object weight (N), friction coefficient and friction margin instead of the file's
        ([`with_options()`][mjtvm.grasp.resolve.loaded.Grasp.with_options]).

    Raises
    ------
    ModelError
        Unknown scenario or variant, or a grasp file that does not load.
    """
    return load_grasp(source, hand=variant).with_options(mg=mg, mu=mu, friction_margin=friction_margin)


def scenario_document(name: str | Path | Mapping[str, Any], **options: Any) -> dict[str, Any]:
    """The ``mjtvm.state/1`` document of a scenario's state (``options`` go to [`load_scenario()`][mjtvm.paper_hand.scenario.load_scenario])."""
    return state_to_dict(load_scenario(name, **options).state())


def grasp_document(doc: Mapping[str, Any], variant: str) -> dict[str, Any]:
    r"""The ``mjtvm.grasp/1`` document of one scenario variant at its stored IK solution.

    The grasp is the paper's hand (``models/paper_hand/<model>``) at the solution's
    joint angles with the object at ``object_position``; REFS = the weight ``mg`` along
    gravity; the fingers' joints in finger order; ignored geoms as ``ignore``.
    """
    v = scenario_variant(doc, variant)
    if "solution" not in v:
        raise ModelError(
            f"scenario {doc['name']!r}", f"variant {variant!r} has no solution: run the generator"
        )
    joints = [n for i in doc["fingers"] for n in finger_joint_names(int(i), v["finger_joints"])]
    contacts = []
    for geom, kind in doc["contact_types"].items():
        entry: dict[str, Any] = {"geom": geom, "type": kind}
        if geom in doc["slide_directions"]:
            entry["slide"] = [float(x) for x in doc["slide_directions"][geom]]
        contacts.append(entry)
    out: dict[str, Any] = {
        "schema": "mjtvm.grasp/1",
        "name": grasp_file_name(str(doc["name"]), variant)[:-5],
        "description": f"{doc.get('description', '')} Hand: {variant}.".strip(),
        "source": doc.get("source", ""),
        "notes": [
            *doc.get("notes", []),
            "Written by tools/make_scenarios.py from mjtvm/data/scenarios/"
            f"{doc['name']}.json (its IK solution); do not edit by hand.",
        ],
        "model": str(v["model"]),
        "joints": joints,
        "mu": float(doc["mu"]),
    }
    if doc["rvds"] is not None:
        out["rvds"] = [[float(x) for x in r] for r in doc["rvds"]]
    out["object"] = {
        "body": doc["object_body"],
        "position": [float(x) for x in doc["object_position"]],
        "quaternion": [1.0, 0.0, 0.0, 0.0],
    }
    out["configuration"] = {"qpos": {k: float(x) for k, x in v["solution"]["qpos"].items()}}
    refs = np.array(doc["refs"], dtype=float)
    if refs.shape == (1, 6) and np.array_equal(refs[0, [0, 1, 3, 4, 5]], np.zeros(5)) and refs[0, 2] < 0:
        out["refs"] = {"mg": float(-refs[0, 2])}
    else:
        out["refs"] = {"weight": False, "wrenches": refs.tolist()}
    out["ranges"] = {"*": {"dcmotor": True}}
    out["lift"] = {
        "direction": [0.0, 0.0, 1.0],
        "bounds": {k: [float(lo), float(hi)] for k, (lo, hi) in v.get("bounds", {}).items()},
    }
    out["contacts"] = contacts
    ignored = [*doc["ignored_geoms"], *v.get("ignored_geoms", [])]
    if ignored:
        out["ignore"] = [{"geom": g} for g in ignored]
    return out
