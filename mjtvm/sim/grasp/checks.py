r"""The field checks of a ``mjtvm.grasp/1`` document: the format's constants, :class:`GraspError`,
the checker of values (types, bounds, unknown keys) and one check per section of the format
(configuration, contacts, refs, ranges, lift); :mod:`mjtvm.sim.grasp.document` runs them.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

from ...core.bounds import MAX_ABS
from ...errors import ModelError

__all__ = ["SCHEMA", "GraspError", "key_of"]

SCHEMA = "mjtvm.grasp/1"
CONTACT_TYPES = ("F", "L", "S", "D")
SELECTORS = ("geom", "body", "geom_id")
RANGE_SOURCES = ("dcmotor", "datasheet", "actuator", "polygon")
MAX_ITEMS = 256  # contacts, targets, joints, poses, wrenches, RVDS vertices
MAX_DEPTH = 16  # a grasp document nests 6 levels (ranges.<pattern>.datasheet.<key>)

_TOP = {
    "schema",
    "name",
    "description",
    "notes",
    "source",
    "model",
    "object",
    "configuration",
    "joints",
    "mu",
    "friction_edges",
    "slip",
    "contact_tolerance",
    "max_penetration",
    "contacts",
    "ignore",
    "contact_rules",
    "refs",
    "rvds",
    "ranges",
    "lift",
    "supports",
    "joint_losses",
}
SHAPES = {"sphere": 1, "capsule": 2, "ellipsoid": 3, "cylinder": 2, "box": 3}  # geom size entries used
SUPPORT_SHAPES = {**SHAPES, "plane": 3}
_REQUIRED = ("schema", "model", "object", "configuration")  # and contacts or contact_rules


class GraspError(ModelError):
    """A grasp file breaks the ``mjtvm.grasp/1`` format or does not fit its model.

    Attributes
    ----------
    file
        The grasp file (or ``"grasp"`` for a mapping).
    field
        The offending field, e.g. ``"contacts[2].geom"``.
    beyond_schema
        True when the broken rule is one JSON Schema cannot state
        (:data:`mjtvm.sim.grasp.validate.BEYOND_SCHEMA`): the schema accepts the document.
    """

    def __init__(self, file: str, field: str, problem: str, *, beyond_schema: bool = False) -> None:
        self.file, self.field, self.beyond_schema = file, field, beyond_schema
        super().__init__(f"{file}: {field}" if field else file, problem)


class _Checker:
    """Field checks that raise :class:`GraspError` naming the field."""

    def __init__(self, file: str) -> None:
        self.file = file

    def fail(self, field: str, problem: str) -> GraspError:
        return GraspError(self.file, field, problem)

    def beyond(self, field: str, problem: str) -> GraspError:
        """A rule of :data:`~mjtvm.sim.grasp.validate.BEYOND_SCHEMA` broken."""
        return GraspError(self.file, field, problem, beyond_schema=True)

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
        # JSON Schema counts 16.0 as an integer; the reader does too, so that it and
        # grasp.schema.json accept the same documents
        whole = isinstance(value, int) or (isinstance(value, float) and value.is_integer())
        if isinstance(value, bool) or not whole or not low <= value <= high:
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
                raise self.beyond(f"{field}.{key_of(k)}", f"expected low < high, got [{lo:g}, {hi:g}]")
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
            raise c.beyond(field, f"nested deeper than {MAX_DEPTH} levels")
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
        raise c.beyond(field, f"expected a {what} without NUL characters, got {text[:40]!r}")
    try:
        text.encode("utf-8")
    except UnicodeEncodeError as e:
        raise c.beyond(
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
    if not isinstance(shape, str) or shape not in shapes:
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
        raise c.beyond(field, f"expected a unit quaternion (w, x, y, z), got norm {norm:.6g}")
    return [x / norm for x in q]


def _qpos(c: _Checker, value: Any) -> dict[str, float | list[float]]:
    """``configuration.qpos``: joint = a number (hinge, slide) or a free joint's 7 numbers."""
    field = "configuration.qpos"
    if not isinstance(value, Mapping) or len(value) > MAX_ITEMS:
        raise c.fail(
            field, f"expected a table of joint = number (or a free joint's 7 numbers), got {_kind(value)}"
        )
    out: dict[str, float | list[float]] = {}
    for k, v in value.items():
        name = f"{field}.{key_of(k)}"
        if isinstance(v, list):
            if len(v) != 7:
                raise c.fail(
                    name, f"expected a free joint's 7 numbers [x, y, z, qw, qx, qy, qz], got {_kind(v)}"
                )
            pose = c.vector(v, name, 7)
            norm = math.sqrt(sum(x * x for x in pose[3:]))
            if abs(norm - 1.0) > 1e-6:
                raise c.beyond(
                    name, f"expected a unit quaternion (w, x, y, z) in numbers 4 to 7, got norm {norm:.6g}"
                )
            out[str(k)] = pose[:3] + [x / norm for x in pose[3:]]
        else:
            out[str(k)] = c.number(v, name)
    return out


def _base(c: _Checker, value: Any) -> dict[str, Any]:
    """``configuration.base``: the pose of a mocap body or of a body on a free joint."""
    t = c.table(value, "configuration.base", {"body", "position", "quaternion"}, ("body",))
    if "position" not in t and "quaternion" not in t:
        raise c.fail("configuration.base", "expected position, quaternion or both")
    return {
        "body": c.string(t["body"], "configuration.base.body"),
        "position": c.vector(t["position"], "configuration.base.position", 3) if "position" in t else None,
        "quaternion": _quaternion(c, t["quaternion"], "configuration.base.quaternion")
        if "quaternion" in t
        else None,
    }


def _configuration(c: _Checker, value: Any) -> dict[str, Any]:
    t = c.table(value, "configuration", {"keyframe", "qpos", "ik", "base"})
    chosen = [k for k in ("keyframe", "qpos", "ik") if k in t]
    if len(chosen) != 1:
        raise c.fail("configuration", f"expected exactly one of keyframe, qpos, ik, got {len(chosen)}")
    base = {"base": _base(c, t["base"])} if "base" in t else {}
    if "keyframe" in t:
        return {"keyframe": c.string(t["keyframe"], "configuration.keyframe"), **base}
    if "qpos" in t:
        return {"qpos": _qpos(c, t["qpos"]), **base}
    ik = c.table(
        t["ik"],
        "configuration.ik",
        {"targets", "start", "bounds", "tolerance", "max_iterations"},
        ("targets",),
    )
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
        out_targets.append(
            {
                kind: c.string(tt[kind], f"{field}.{kind}"),
                "point": c.vector(tt["point"], f"{field}.point", 3) if "point" in tt else None,
            }
        )
    return {
        "ik": {
            "targets": out_targets,
            "start": c.number_map(ik.get("start", {}), "configuration.ik.start"),
            "bounds": c.bounds(ik.get("bounds", {}), "configuration.ik.bounds"),
            "tolerance": c.number(ik.get("tolerance", 1e-6), "configuration.ik.tolerance", positive=True),
            "max_iterations": c.integer(
                ik.get("max_iterations", 200), "configuration.ik.max_iterations", 1, 10_000
            ),
        },
        **base,
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
                raise c.beyond(f"{field}.slide", "expected a non-zero direction")
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
        raise c.beyond("refs", "no weight and no non-zero wrench: the REFS would be the origin only")
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
        named = isinstance(t[source], str) and 0 < len(t[source]) <= 1000
        if source in ("dcmotor", "actuator") and not (t[source] is True or named):
            raise c.fail(f"{field}.{source}", f"expected true or an actuator name, got {_kind(t[source])}")
        if source == "datasheet" and not (named or isinstance(t["datasheet"], Mapping)):
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
            raise c.beyond("lift.direction", "expected a non-zero direction")
        out["direction"] = d
    if "twist" in t:
        w = c.vector(t["twist"], "lift.twist", 6)
        if not any(w):
            raise c.beyond("lift.twist", "expected a non-zero twist")
        out["twist"] = w
    if "poses" in t:
        poses = t["poses"]
        if not isinstance(poses, list) or len(poses) < 2 or len(poses) > MAX_ITEMS:
            raise c.fail("lift.poses", f"expected a list of 2 to {MAX_ITEMS} poses")
        out["poses"] = []
        for i, p in enumerate(poses):
            pt = c.table(p, f"lift.poses[{i}]", {"position", "quaternion"}, ("position",))
            out["poses"].append(
                {
                    "position": c.vector(pt["position"], f"lift.poses[{i}].position", 3),
                    "quaternion": _quaternion(c, pt["quaternion"], f"lift.poses[{i}].quaternion")
                    if "quaternion" in pt
                    else None,
                }
            )
    out["height"] = c.number(t["height"], "lift.height", positive=True) if "height" in t else None
    out["stop_margin"] = (
        c.number(t["stop_margin"], "lift.stop_margin", low=0.0) if "stop_margin" in t else None
    )
    if out["stop_margin"] is not None and out["stop_margin"] >= 1.0:
        raise c.fail("lift.stop_margin", f"expected a fraction in [0, 1), got {out['stop_margin']:g}")
    out["bounds"] = c.bounds(t.get("bounds", {}), "lift.bounds")
    return out


# ------------------------------------------------------------------ writing
