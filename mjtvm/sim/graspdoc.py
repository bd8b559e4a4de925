r"""Reading and checking a ``mjtvm.grasp/1`` document (``docs/grasp-format.md``).

:func:`read_grasp_document` reads a TOML or JSON grasp file (or takes a mapping) and checks
its structure field by field: unknown keys, wrong types, missing or conflicting choices
(one of ``keyframe``/``qpos``/``ik``; one selector per contact; one source per operation
range) and numbers outside the format's bounds are each one :class:`GraspError` naming the
field, e.g. ``contacts[2].type: expected one of F, L, S, D, got 'X'``. Names are checked
against the model later (:mod:`mjtvm.sim.graspfile`). The JSON Schema
``mjtvm/data/schema/grasp.schema.json`` states the same structure for other tools.
"""

from __future__ import annotations

import json
import math
import tomllib
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from ..core.bounds import MAX_ABS, MAX_FILE_BYTES, MAX_FRICTION_EDGES, MIN_FRICTION_EDGES
from ..errors import ModelError

__all__ = ["SCHEMA", "GraspError", "format_toml", "read_grasp_document"]

SCHEMA = "mjtvm.grasp/1"
CONTACT_TYPES = ("F", "L", "S", "D")
SELECTORS = ("geom", "body", "geom_id")
RANGE_SOURCES = ("dcmotor", "datasheet", "actuator", "polygon")
MAX_ITEMS = 256  # contacts, targets, joints, poses, wrenches, RVDS vertices
MAX_DEPTH = 16  # a grasp document nests 6 levels (ranges.<pattern>.datasheet.<key>)

_TOP = {
    "schema", "name", "description", "notes", "source", "model", "object", "configuration", "joints",
    "mu", "friction_edges", "slip", "contact_tolerance", "contacts", "ignore", "refs", "rvds",
    "ranges", "lift", "supports", "joint_losses",
}  # fmt: skip
SHAPES = {"sphere": 1, "capsule": 2, "ellipsoid": 3, "cylinder": 2, "box": 3}  # geom size entries used
SUPPORT_SHAPES = {**SHAPES, "plane": 3}
_REQUIRED = ("schema", "model", "object", "configuration", "contacts")


class GraspError(ModelError):
    """A grasp file breaks the ``mjtvm.grasp/1`` format or does not fit its model.

    Attributes
    ----------
    file
        The grasp file (or ``"grasp"`` for a mapping).
    field
        The offending field, e.g. ``"contacts[2].geom"``.
    """

    def __init__(self, file: str, field: str, problem: str) -> None:
        self.file, self.field = file, field
        super().__init__(f"{file}: {field}" if field else file, problem)


class _Checker:
    """Field checks that raise :class:`GraspError` naming the field."""

    def __init__(self, file: str) -> None:
        self.file = file

    def fail(self, field: str, problem: str) -> GraspError:
        return GraspError(self.file, field, problem)

    def table(
        self, value: Any, field: str, allowed: set[str], required: Sequence[str] = ()
    ) -> Mapping[str, Any]:
        if not isinstance(value, Mapping):
            raise self.fail(field, f"expected a table (object), got {_kind(value)}")
        unknown = sorted(key_of(k) for k in value if k not in allowed)
        if unknown:
            raise self.fail(
                f"{field}.{unknown[0]}" if field else unknown[0],
                f"unknown key (allowed: {', '.join(sorted(allowed))})",
            )
        for key in required:
            if key not in value:
                raise self.fail(f"{field}.{key}" if field else key, "required")
        return value

    def string(self, value: Any, field: str) -> str:
        if not isinstance(value, str) or not value or len(value) > 1000:
            raise self.fail(field, f"expected a non-empty string, got {_kind(value)}")
        return value

    def number(self, value: Any, field: str, *, low: float | None = None, positive: bool = False) -> float:
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise self.fail(field, f"expected a number, got {_kind(value)}")
        x = float(value) if abs(value) < 1e300 else math.inf
        if not math.isfinite(x) or abs(x) > MAX_ABS:
            raise self.fail(field, f"expected a finite number with |x| <= {MAX_ABS:g}, got {value!r}")
        if (low is not None and x < low) or (positive and x <= 0):
            raise self.fail(field, f"expected a number {'> 0' if positive else f'>= {low:g}'}, got {value!r}")
        return x

    def integer(self, value: Any, field: str, low: int, high: int) -> int:
        if isinstance(value, bool) or not isinstance(value, int) or not low <= value <= high:
            raise self.fail(field, f"expected an integer in [{low}, {high}], got {value!r}")
        return int(value)

    def vector(self, value: Any, field: str, n: int) -> list[float]:
        if not isinstance(value, list) or len(value) != n:
            raise self.fail(field, f"expected a list of {n} numbers, got {_kind(value)}")
        return [self.number(x, f"{field}[{i}]") for i, x in enumerate(value)]

    def vectors(self, value: Any, field: str, n: int) -> list[list[float]]:
        if not isinstance(value, list) or not value or len(value) > MAX_ITEMS:
            raise self.fail(field, f"expected a list of 1 to {MAX_ITEMS} vectors of {n} numbers")
        return [self.vector(v, f"{field}[{i}]", n) for i, v in enumerate(value)]

    def names(self, value: Any, field: str) -> list[str]:
        if not isinstance(value, list) or not value or len(value) > MAX_ITEMS:
            raise self.fail(field, f"expected a list of 1 to {MAX_ITEMS} names")
        return [self.string(v, f"{field}[{i}]") for i, v in enumerate(value)]

    def number_map(self, value: Any, field: str) -> dict[str, float]:
        if not isinstance(value, Mapping) or len(value) > MAX_ITEMS:
            raise self.fail(field, f"expected a table of name = number, got {_kind(value)}")
        return {str(k): self.number(v, f"{field}.{key_of(k)}") for k, v in value.items()}

    def bounds(self, value: Any, field: str) -> dict[str, tuple[float, float]]:
        if not isinstance(value, Mapping) or len(value) > MAX_ITEMS:
            raise self.fail(field, f"expected a table of joint = [low, high], got {_kind(value)}")
        out = {}
        for k, v in value.items():
            lo, hi = self.vector(v, f"{field}.{key_of(k)}", 2)
            if not lo < hi:
                raise self.fail(f"{field}.{key_of(k)}", f"expected low < high, got [{lo:g}, {hi:g}]")
            out[str(k)] = (lo, hi)
        return out

    def selector(self, value: Any, field: str, extra: set[str]) -> dict[str, Any]:
        t = self.table(value, field, {*SELECTORS, *extra})
        chosen = [k for k in SELECTORS if k in t]
        if len(chosen) != 1:
            raise self.fail(field, f"expected exactly one of {', '.join(SELECTORS)}, got {len(chosen)}")
        key = chosen[0]
        target = (
            self.integer(t[key], f"{field}.{key}", 0, 10**6)
            if key == "geom_id"
            else self.string(t[key], f"{field}.{key}")
        )
        return {"select": key, "target": target, **{k: v for k, v in t.items() if k not in SELECTORS}}


def key_of(key: Any) -> str:
    """A key of the document as a field name: as written when it prints on one line, else its
    ``repr`` (``'fro\\nbnicate'``), so that an error naming it stays one line."""
    text = str(key)
    return text if text.isprintable() and text == text.strip() and text else repr(text)


def _check_text(doc: Mapping[str, Any], c: _Checker) -> None:
    """Refuse a lone surrogate (JSON's ``"\\ud800"``) or a NUL character in any key or string:
    neither reaches MuJoCo's C names (nor a UTF-8 stream) intact."""
    stack: list[tuple[Any, str, int]] = [(doc, "", 0)]
    while stack:
        node, field, depth = stack.pop()
        if depth > MAX_DEPTH and isinstance(node, (Mapping, list)):  # also a mapping that holds itself
            raise c.fail(field, f"nested deeper than {MAX_DEPTH} levels")
        if isinstance(node, Mapping):
            for key, value in node.items():
                name = f"{field}.{key_of(key)}" if field else key_of(key)
                _check_string(str(key), name, c, "key")
                stack.append((value, name, depth + 1))
        elif isinstance(node, list):
            stack.extend((value, f"{field}[{i}]", depth + 1) for i, value in enumerate(node))
        elif isinstance(node, str):
            _check_string(node, field, c, "string")


def _check_string(text: str, field: str, c: _Checker, what: str) -> None:
    if "\0" in text:
        raise c.fail(field, f"expected a {what} without NUL characters, got {text[:40]!r}")
    try:
        text.encode("utf-8")
    except UnicodeEncodeError as e:
        raise c.fail(
            field,
            f"expected a {what} of valid Unicode text, got a lone surrogate {text[e.start]!r} in {text[:40]!r}",
        ) from e


def _kind(value: Any) -> str:
    if value is None:
        return "nothing"
    if isinstance(value, bool):
        return f"a boolean ({str(value).lower()})"
    if isinstance(value, (int, float)):
        return f"the number {value!r}"
    if isinstance(value, str):
        return f"the string {value[:40]!r}"
    if isinstance(value, list):
        return f"a list of {len(value)}"
    if isinstance(value, Mapping):
        return "a table"
    return type(value).__name__


def _load(source: str | Path | Mapping[str, Any]) -> tuple[dict[str, Any], Path | None, str]:
    """The raw document, its path (None for a mapping) and a label for messages."""
    if isinstance(source, Mapping):
        return dict(source), None, "grasp"
    path = Path(source)
    label = str(path)
    if path.suffix.lower() not in (".toml", ".json"):
        raise GraspError(label, "", f"expected a .toml or .json file, got {path.suffix or 'no suffix'!r}")
    try:
        with path.open("rb") as f:
            raw = f.read(MAX_FILE_BYTES + 1)
    except (OSError, ValueError) as e:
        raise GraspError(label, "", f"cannot read the grasp file: {getattr(e, 'strerror', None) or e}") from e
    if len(raw) > MAX_FILE_BYTES:
        raise GraspError(label, "", f"larger than {MAX_FILE_BYTES} bytes: not a grasp file")
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as e:
        raise GraspError(label, "", f"not UTF-8 text: byte 0x{raw[e.start]:02x} at offset {e.start}") from e
    if path.suffix.lower() == ".toml":
        try:
            doc: Any = tomllib.loads(text)
        except tomllib.TOMLDecodeError as e:
            raise GraspError(label, "", f"malformed TOML: {e}") from e
    else:
        try:
            doc = json.loads(text)
        except (json.JSONDecodeError, RecursionError, ValueError) as e:
            raise GraspError(label, "", f"malformed JSON: {e}") from e
    if not isinstance(doc, dict):
        raise GraspError(label, "", "expected a table (JSON object) at the top level")
    return doc, path, label


def read_grasp_document(source: str | Path | Mapping[str, Any]) -> tuple[dict[str, Any], Path | None]:
    r"""The checked grasp document and the file's path (``None`` for a mapping).

    The returned document is normalised: selectors as ``{"select": "geom"|"body"|"geom_id",
    "target": ...}``; numbers as floats; defaults filled in (``mu`` None, ``friction_edges``
    16, ``slip`` ``"per_contact"``, ``contact_tolerance`` 1e-4 m, ``refs`` the weight,
    ``rvds`` None, ``ranges`` {}, ``lift`` None, ``ignore`` []).

    Raises
    ------
    GraspError
        Unreadable file, malformed TOML/JSON, or a field breaking the format (named).
    """
    raw, path, label = _load(source)
    c = _Checker(label)
    _check_text(raw, c)
    doc = dict(c.table(raw, "", _TOP, _REQUIRED))
    if doc["schema"] != SCHEMA:
        raise c.fail("schema", f"expected {SCHEMA!r}, got {doc['schema']!r}")
    doc["name"] = c.string(doc.get("name", path.stem if path else "grasp"), "name")
    doc["model"] = c.string(doc["model"], "model")
    obj = c.table(
        doc["object"], "object", {"body", "position", "quaternion", "shape", "size", "mass"}, ("body",)
    )
    doc["object"] = {
        "body": c.string(obj["body"], "object.body"),
        "position": c.vector(obj["position"], "object.position", 3) if "position" in obj else None,
        "quaternion": _quaternion(c, obj["quaternion"], "object.quaternion") if "quaternion" in obj else None,
        **_shape(c, obj, "object", SHAPES, mass=True),
    }
    supports = doc.get("supports", [])
    if not isinstance(supports, list) or len(supports) > MAX_ITEMS:
        raise c.fail("supports", f"expected a list of support geoms to add, got {_kind(supports)}")
    doc["supports"] = []
    for i, item in enumerate(supports):
        t = c.table(
            item,
            f"supports[{i}]",
            {"name", "shape", "size", "position", "quaternion"},
            ("name", "shape", "size"),
        )
        doc["supports"].append({
            "name": c.string(t["name"], f"supports[{i}].name"),
            "position": c.vector(t["position"], f"supports[{i}].position", 3) if "position" in t else [0.0] * 3,
            "quaternion": _quaternion(c, t["quaternion"], f"supports[{i}].quaternion") if "quaternion" in t
            else [1.0, 0.0, 0.0, 0.0],
            **_shape(c, t, f"supports[{i}]", SUPPORT_SHAPES, mass=False),
        })  # fmt: skip
    doc["configuration"] = _configuration(c, doc["configuration"])
    doc["joints"] = c.names(doc["joints"], "joints") if "joints" in doc else None
    doc["mu"] = c.number(doc["mu"], "mu", low=0.0) if "mu" in doc else None
    doc["friction_edges"] = c.integer(doc.get("friction_edges", 16), "friction_edges", MIN_FRICTION_EDGES,
                                      MAX_FRICTION_EDGES)  # fmt: skip
    doc["slip"] = doc.get("slip", "per_contact")
    if doc["slip"] not in ("per_contact", "shared"):
        raise c.fail("slip", f"expected 'per_contact' or 'shared', got {doc['slip']!r}")
    doc["contact_tolerance"] = c.number(doc.get("contact_tolerance", 1e-4), "contact_tolerance", low=0.0)
    if doc["contact_tolerance"] > 0.01:
        raise c.fail("contact_tolerance", f"expected at most 0.01 m, got {doc['contact_tolerance']:g}")
    doc["contacts"] = _contacts(c, doc["contacts"])
    ignore = doc.get("ignore", [])
    if not isinstance(ignore, list) or len(ignore) > MAX_ITEMS:
        raise c.fail("ignore", f"expected a list of selections (geom, body or geom_id), got {_kind(ignore)}")
    doc["ignore"] = [c.selector(s, f"ignore[{i}]", set()) for i, s in enumerate(ignore)]
    doc["refs"] = _refs(c, doc.get("refs", {}))
    doc["rvds"] = c.vectors(doc["rvds"], "rvds", 6) if doc.get("rvds") is not None else None
    doc["ranges"] = _ranges(c, doc.get("ranges", {}))
    doc["joint_losses"] = doc.get("joint_losses", "fold")
    if doc["joint_losses"] not in ("fold", "ignore"):
        raise c.fail("joint_losses", f"expected 'fold' or 'ignore', got {doc['joint_losses']!r}")
    doc["lift"] = _lift(c, doc["lift"]) if "lift" in doc else None
    return doc, path


def _shape(
    c: _Checker, t: Mapping[str, Any], field: str, shapes: Mapping[str, int], *, mass: bool
) -> dict[str, Any]:
    """``shape``, ``size`` (and ``mass``) of a geom to add; all None for an existing object body."""
    if "shape" not in t:
        for key in ("size", "mass"):
            if key in t:
                raise c.fail(f"{field}.{key}", "only with shape (a body to add)")
        return {"shape": None, "size": None, "mass": None} if mass else {}
    shape = t["shape"]
    if shape not in shapes:
        raise c.fail(f"{field}.shape", f"expected one of {', '.join(shapes)}, got {shape!r}")
    n = shapes[shape]
    size = t.get("size")
    if not isinstance(size, list) or len(size) != n:
        raise c.fail(
            f"{field}.size", f"expected {n} numbers (MuJoCo's size of a {shape}, m), got {_kind(size)}"
        )
    out: dict[str, Any] = {
        "shape": shape,
        "size": [c.number(x, f"{field}.size[{i}]", positive=True) for i, x in enumerate(size)],
    }
    if mass:
        if "mass" not in t:
            raise c.fail(f"{field}.mass", "required with shape (kg)")
        out["mass"] = c.number(t["mass"], f"{field}.mass", positive=True)
    return out


def _quaternion(c: _Checker, value: Any, field: str) -> list[float]:
    q = c.vector(value, field, 4)
    norm = math.sqrt(sum(x * x for x in q))
    if abs(norm - 1.0) > 1e-6:
        raise c.fail(field, f"expected a unit quaternion (w, x, y, z), got norm {norm:.6g}")
    return [x / norm for x in q]


def _configuration(c: _Checker, value: Any) -> dict[str, Any]:
    t = c.table(value, "configuration", {"keyframe", "qpos", "ik"})
    chosen = [k for k in ("keyframe", "qpos", "ik") if k in t]
    if len(chosen) != 1:
        raise c.fail("configuration", f"expected exactly one of keyframe, qpos, ik, got {len(chosen)}")
    if "keyframe" in t:
        return {"keyframe": c.string(t["keyframe"], "configuration.keyframe")}
    if "qpos" in t:
        return {"qpos": c.number_map(t["qpos"], "configuration.qpos")}
    ik = c.table(t["ik"], "configuration.ik", {"targets", "start", "bounds", "tolerance", "max_iterations"},
                 ("targets",))  # fmt: skip
    targets = ik["targets"]
    if not isinstance(targets, list) or not targets or len(targets) > MAX_ITEMS:
        raise c.fail("configuration.ik.targets", "expected a list of 1 or more targets")
    out_targets = []
    for i, tg in enumerate(targets):
        field = f"configuration.ik.targets[{i}]"
        tt = c.table(tg, field, {"geom", "site", "point"})
        if ("geom" in tt) == ("site" in tt):
            raise c.fail(field, "expected exactly one of geom, site")
        kind = "geom" if "geom" in tt else "site"
        if kind == "site" and "point" not in tt:
            raise c.fail(f"{field}.point", "required for a site target (where the site goes, m)")
        out_targets.append({
            kind: c.string(tt[kind], f"{field}.{kind}"),
            "point": c.vector(tt["point"], f"{field}.point", 3) if "point" in tt else None,
        })  # fmt: skip
    return {
        "ik": {
            "targets": out_targets,
            "start": c.number_map(ik.get("start", {}), "configuration.ik.start"),
            "bounds": c.bounds(ik.get("bounds", {}), "configuration.ik.bounds"),
            "tolerance": c.number(ik.get("tolerance", 1e-6), "configuration.ik.tolerance", positive=True),
            "max_iterations": c.integer(
                ik.get("max_iterations", 200), "configuration.ik.max_iterations", 1, 10_000
            ),
        }
    }


def _contacts(c: _Checker, value: Any) -> list[dict[str, Any]]:
    if not isinstance(value, list) or not value or len(value) > MAX_ITEMS:
        raise c.fail("contacts", f"expected a list of 1 to {MAX_ITEMS} contact tables, got {_kind(value)}")
    out = []
    for i, item in enumerate(value):
        field = f"contacts[{i}]"
        s = c.selector(item, field, {"type", "mu", "slide", "preload"})
        if "type" not in s:
            raise c.fail(f"{field}.type", "required (F, L, S or D)")
        if s["type"] not in CONTACT_TYPES:
            raise c.fail(f"{field}.type", f"expected one of {', '.join(CONTACT_TYPES)}, got {s['type']!r}")
        if "mu" in s:
            s["mu"] = c.number(s["mu"], f"{field}.mu", low=0.0)
        if "preload" in s:
            s["preload"] = c.number(s["preload"], f"{field}.preload", low=0.0)
            if s["preload"] > 0.0 and s["type"] == "D":
                raise c.fail(f"{field}.preload", "a D contact carries no force: its preload must be 0")
        if "slide" in s:
            if s["type"] != "S":
                raise c.fail(f"{field}.slide", "only an S contact has a slide direction")
            s["slide"] = c.vector(s["slide"], f"{field}.slide", 3)
            if math.sqrt(sum(x * x for x in s["slide"])) < 1e-12:
                raise c.fail(f"{field}.slide", "expected a non-zero direction")
        out.append(s)
    return out


def _refs(c: _Checker, value: Any) -> dict[str, Any]:
    t = c.table(value, "refs", {"weight", "mg", "wrenches"})
    weight = t.get("weight", True)
    if not isinstance(weight, bool):
        raise c.fail("refs.weight", f"expected true or false, got {_kind(weight)}")
    mg = c.number(t["mg"], "refs.mg", low=0.0) if "mg" in t else None
    if mg is not None and not weight:
        raise c.fail("refs.mg", "given with weight = false")
    wrenches = c.vectors(t["wrenches"], "refs.wrenches", 6) if "wrenches" in t else [[0.0] * 6]
    if not weight and not any(any(w) for w in wrenches):
        raise c.fail("refs", "no weight and no non-zero wrench: the REFS would be the origin only")
    return {"weight": weight, "mg": mg, "wrenches": wrenches}


def _ranges(c: _Checker, value: Any) -> dict[str, dict[str, Any]]:
    if not isinstance(value, Mapping) or len(value) > MAX_ITEMS:
        raise c.fail("ranges", f"expected a table of joint (or pattern) = range, got {_kind(value)}")
    out = {}
    for key, entry in value.items():
        field = f"ranges.{key_of(key)}"
        t = dict(c.table(entry, field, {*RANGE_SOURCES, "gear_ratio", "gear_efficiency", "speed_limit"}))
        chosen = [k for k in RANGE_SOURCES if k in t]
        if len(chosen) != 1:
            raise c.fail(field, f"expected exactly one of {', '.join(RANGE_SOURCES)}, got {len(chosen)}")
        source = chosen[0]
        for k in ("gear_ratio", "gear_efficiency"):
            if k in t:
                if source != "datasheet":
                    raise c.fail(f"{field}.{k}", "only with datasheet")
                t[k] = c.number(t[k], f"{field}.{k}", positive=True)
        if "speed_limit" in t:
            if source != "actuator":
                raise c.fail(
                    f"{field}.speed_limit", "only with actuator (the joint speed of the approximation)"
                )
            t["speed_limit"] = c.number(t["speed_limit"], f"{field}.speed_limit", positive=True)
        elif source == "actuator":
            raise c.fail(f"{field}.speed_limit", "required with actuator (joint speed limit, rad/s)")
        if source in ("dcmotor", "actuator") and not (t[source] is True or isinstance(t[source], str)):
            raise c.fail(f"{field}.{source}", f"expected true or an actuator name, got {_kind(t[source])}")
        if source == "datasheet" and not isinstance(t["datasheet"], (str, Mapping)):
            raise c.fail(f"{field}.datasheet", "expected a datasheet name, a JSON path or a table")
        if source == "polygon":
            t["polygon"] = c.vectors(t["polygon"], f"{field}.polygon", 2)
        out[str(key)] = {"source": source, **t}
    return out


def _lift(c: _Checker, value: Any) -> dict[str, Any]:
    t = c.table(value, "lift", {"direction", "twist", "poses", "height", "bounds", "stop_margin"})
    chosen = [k for k in ("direction", "twist", "poses") if k in t]
    if len(chosen) > 1:
        raise c.fail("lift", f"expected at most one of direction, twist, poses, got {', '.join(chosen)}")
    out: dict[str, Any] = {"direction": None, "twist": None, "poses": None}
    if "direction" in t:
        d = c.vector(t["direction"], "lift.direction", 3)
        if math.sqrt(sum(x * x for x in d)) < 1e-12:
            raise c.fail("lift.direction", "expected a non-zero direction")
        out["direction"] = d
    if "twist" in t:
        w = c.vector(t["twist"], "lift.twist", 6)
        if not any(w):
            raise c.fail("lift.twist", "expected a non-zero twist")
        out["twist"] = w
    if "poses" in t:
        poses = t["poses"]
        if not isinstance(poses, list) or len(poses) < 2 or len(poses) > MAX_ITEMS:
            raise c.fail("lift.poses", f"expected a list of 2 to {MAX_ITEMS} poses")
        out["poses"] = []
        for i, p in enumerate(poses):
            pt = c.table(p, f"lift.poses[{i}]", {"position", "quaternion"}, ("position",))
            out["poses"].append({
                "position": c.vector(pt["position"], f"lift.poses[{i}].position", 3),
                "quaternion": _quaternion(c, pt["quaternion"], f"lift.poses[{i}].quaternion")
                if "quaternion" in pt else None,
            })  # fmt: skip
    out["height"] = c.number(t["height"], "lift.height", positive=True) if "height" in t else None
    out["stop_margin"] = (
        c.number(t["stop_margin"], "lift.stop_margin", low=0.0) if "stop_margin" in t else None
    )
    if out["stop_margin"] is not None and out["stop_margin"] >= 1.0:
        raise c.fail("lift.stop_margin", f"expected a fraction in [0, 1), got {out['stop_margin']:g}")
    out["bounds"] = c.bounds(t.get("bounds", {}), "lift.bounds")
    return out


# ------------------------------------------------------------------ writing
def _toml_value(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (int, float)):
        text = repr(float(value)) if isinstance(value, float) else str(value)
        return text if math.isfinite(float(value)) else "nan"  # the reader refuses nan
    if isinstance(value, str):
        return json.dumps(value, ensure_ascii=False)  # a JSON string is a TOML basic string
    if isinstance(value, list):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    if isinstance(value, Mapping):
        return "{ " + ", ".join(f"{_toml_key(k)} = {_toml_value(v)}" for k, v in value.items()) + " }"
    raise TypeError(f"no TOML form for {type(value).__name__}")


def _toml_key(key: str) -> str:
    return key if key.replace("_", "").replace("-", "").isalnum() and key.isascii() else json.dumps(key)


def format_toml(doc: Mapping[str, Any]) -> str:
    """TOML text of a grasp document: scalars and lists at the top (a list of strings one item
    per line), then one ``[table]`` per mapping (a mapping of more than three entries inside
    it as its own ``[table.key]``), then ``[[array]]`` per list of mappings. Floats as
    ``repr``: ``tomllib`` reads back the same doubles."""
    head, tables, arrays = [], [], []
    for key, value in doc.items():
        k = _toml_key(key)
        if isinstance(value, Mapping):
            rows, subs = [], []
            for a, b in value.items():
                if isinstance(b, Mapping) and len(b) > 3:
                    body = "\n".join(f"{_toml_key(x)} = {_toml_value(y)}" for x, y in b.items())
                    subs.append(f"\n[{k}.{_toml_key(a)}]\n{body}\n")
                else:
                    rows.append(f"{_toml_key(a)} = {_toml_value(b)}")
            tables.append(f"\n[{k}]\n" + "".join(r + "\n" for r in rows) + "".join(subs))
        elif isinstance(value, list) and value and all(isinstance(v, Mapping) for v in value):
            for item in value:
                rows = [f"{_toml_key(a)} = {_toml_value(b)}\n" for a, b in item.items()]
                arrays.append(f"\n[[{k}]]\n" + "".join(rows))
        elif isinstance(value, list) and value and all(isinstance(v, (str, list)) for v in value):
            head.append(f"{k} = [\n" + "".join(f"  {_toml_value(v)},\n" for v in value) + "]")
        else:
            head.append(f"{k} = {_toml_value(value)}")
    return "\n".join(head) + "\n" + "".join(tables) + "".join(arrays)
