r"""The section checks of a ``mjtvm.grasp/1`` document (configuration, contacts, contact rules,
refs, ranges, lift, joint limits), built on the value checks of `mjtvm.grasp.document.checks`;
`mjtvm.grasp.document.document` runs them. Each takes the `Checker` naming the file and the
section's raw value and returns it normalised, or raises a `GraspError` naming the first bad
field. None needs the model: names are checked against it in `mjtvm.grasp.resolve`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from mjtvm.grasp.document.checks import CONTACT_TYPES, MAX_ITEMS, RANGE_SOURCES, Checker, key_of, kind_of
from mjtvm.model.limits import DEFAULT_HORIZON, DEFAULT_TOLERANCE

__all__ = [
    "RULE_TYPES",
    "JointLimitOptions",
    "check_configuration",
    "check_contact_rules",
    "check_contacts",
    "check_joint_limits",
    "check_lift",
    "check_quaternion",
    "check_ranges",
    "check_refs",
    "check_shape",
    "mu_range",
]

RULE_TYPES = ("F", "L", "D", "ignore")
_RULE_KEYS = {"geom", "body", "type", "mu"}


def check_shape(
    c: Checker, t: Mapping[str, Any], field: str, shapes: Mapping[str, int], *, mass: bool
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
            f"{field}.size", f"expected {n} numbers (MuJoCo's size of a {shape}, m), got {kind_of(size)}"
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


def check_quaternion(c: Checker, value: Any, field: str) -> list[float]:
    q = c.vector(value, field, 4)
    norm = math.sqrt(sum(x * x for x in q))
    if abs(norm - 1.0) > 1e-6:
        raise c.beyond(field, f"expected a unit quaternion (w, x, y, z), got norm {norm:.6g}")
    return [x / norm for x in q]


def _qpos(c: Checker, value: Any) -> dict[str, float | list[float]]:
    """``configuration.qpos``: joint = a number (hinge, slide) or a free joint's 7 numbers."""
    field = "configuration.qpos"
    if not isinstance(value, Mapping) or len(value) > MAX_ITEMS:
        raise c.fail(
            field, f"expected a table of joint = number (or a free joint's 7 numbers), got {kind_of(value)}"
        )
    out: dict[str, float | list[float]] = {}
    for k, v in value.items():
        name = f"{field}.{key_of(k)}"
        if isinstance(v, list):
            if len(v) != 7:
                raise c.fail(
                    name, f"expected a free joint's 7 numbers [x, y, z, qw, qx, qy, qz], got {kind_of(v)}"
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


def _base(c: Checker, value: Any) -> dict[str, Any]:
    """``configuration.base``: the pose of a mocap body or of a body on a free joint."""
    t = c.table(value, "configuration.base", {"body", "position", "quaternion"}, ("body",))
    if "position" not in t and "quaternion" not in t:
        raise c.fail("configuration.base", "expected position, quaternion or both")
    return {
        "body": c.string(t["body"], "configuration.base.body"),
        "position": c.vector(t["position"], "configuration.base.position", 3) if "position" in t else None,
        "quaternion": check_quaternion(c, t["quaternion"], "configuration.base.quaternion")
        if "quaternion" in t
        else None,
    }


def check_configuration(c: Checker, value: Any) -> dict[str, Any]:
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


def mu_range(c: Checker, value: Any, field: str) -> tuple[float, float]:
    """A friction interval ``[mu_lo, mu_hi]``, ``0 <= mu_lo <= mu_hi`` (``docs/grasp-format.md``)."""
    lo, hi = c.vector(value, field, 2)
    if not 0.0 <= lo <= hi:
        raise c.beyond(field, f"expected [mu_lo, mu_hi] with 0 <= mu_lo <= mu_hi, got {value!r}")
    return (lo, hi)


def check_contacts(c: Checker, value: Any) -> list[dict[str, Any]]:
    if not isinstance(value, list) or not value or len(value) > MAX_ITEMS:
        raise c.fail("contacts", f"expected a list of 1 to {MAX_ITEMS} contact tables, got {kind_of(value)}")
    out = []
    for i, item in enumerate(value):
        field = f"contacts[{i}]"
        s = c.selector(item, field, {"type", "mu", "slide", "preload", "mu_range"})
        if "type" not in s:
            raise c.fail(f"{field}.type", "required (F, L, S or D)")
        if s["type"] not in CONTACT_TYPES:
            raise c.fail(f"{field}.type", f"expected one of {', '.join(CONTACT_TYPES)}, got {s['type']!r}")
        if "mu" in s:
            s["mu"] = c.number(s["mu"], f"{field}.mu", low=0.0)
        if "mu_range" in s:
            s["mu_range"] = mu_range(c, s["mu_range"], f"{field}.mu_range")
            if s["type"] not in ("F", "S"):
                raise c.beyond(f"{field}.mu_range", "only F and S contacts have friction")
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


def check_refs(c: Checker, value: Any) -> dict[str, Any]:
    t = c.table(value, "refs", {"weight", "mg", "wrenches"})
    weight = t.get("weight", True)
    if not isinstance(weight, bool):
        raise c.fail("refs.weight", f"expected true or false, got {kind_of(weight)}")
    mg = c.number(t["mg"], "refs.mg", low=0.0) if "mg" in t else None
    if mg is not None and not weight:
        raise c.fail("refs.mg", "given with weight = false")
    wrenches = c.vectors(t["wrenches"], "refs.wrenches", 6) if "wrenches" in t else [[0.0] * 6]
    if not weight and not any(any(w) for w in wrenches):
        raise c.beyond("refs", "no weight and no non-zero wrench: the REFS would be the origin only")
    return {"weight": weight, "mg": mg, "wrenches": wrenches}


def check_ranges(c: Checker, value: Any) -> dict[str, dict[str, Any]]:
    if not isinstance(value, Mapping) or len(value) > MAX_ITEMS:
        raise c.fail("ranges", f"expected a table of joint (or pattern) = range, got {kind_of(value)}")
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
            raise c.fail(f"{field}.{source}", f"expected true or an actuator name, got {kind_of(t[source])}")
        if source == "datasheet" and not (named or isinstance(t["datasheet"], Mapping)):
            raise c.fail(f"{field}.datasheet", "expected a datasheet name, a JSON path or a table")
        if source == "polygon":
            t["polygon"] = c.vectors(t["polygon"], f"{field}.polygon", 2)
        out[str(key)] = {"source": source, **t}
    return out


def check_lift(c: Checker, value: Any) -> dict[str, Any]:
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
                    "quaternion": check_quaternion(c, pt["quaternion"], f"lift.poses[{i}].quaternion")
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


def check_contact_rules(c: Checker, value: Any) -> list[dict[str, Any]]:
    """The ``contact_rules`` list normalised to ``{"select": "geom"|"body", "pattern", "type",
    "mu"}`` (``mu`` None when not given); a `GraspError` naming the first bad field."""
    if not isinstance(value, list) or not value or len(value) > MAX_ITEMS:
        raise c.fail(
            "contact_rules", f"expected a list of 1 to {MAX_ITEMS} rule tables, got {kind_of(value)}"
        )
    out = []
    for i, item in enumerate(value):
        field = f"contact_rules[{i}]"
        t = c.table(item, field, _RULE_KEYS)
        chosen = [k for k in ("geom", "body") if k in t]
        if len(chosen) != 1:
            raise c.fail(field, f"expected exactly one of geom, body, got {len(chosen)}")
        if "type" not in t:
            raise c.fail(f"{field}.type", f"required ({', '.join(RULE_TYPES)})")
        if t["type"] not in RULE_TYPES:
            raise c.fail(
                f"{field}.type", f"expected one of {', '.join(RULE_TYPES)}, got {kind_of(t['type'])}"
            )
        mu = c.number(t["mu"], f"{field}.mu", low=0.0) if "mu" in t else None
        if mu is not None and t["type"] == "ignore":
            raise c.fail(f"{field}.mu", "an ignore rule types nothing: no mu")
        select = chosen[0]
        out.append(
            {
                "select": select,
                "pattern": c.string(t[select], f"{field}.{select}"),
                "type": t["type"],
                "mu": mu,
            }
        )
    return out


@dataclass(frozen=True)
class JointLimitOptions:
    """How `grasp_state()` states the joints' position limits (`mjtvm.model.limits`):
    a joint within ``tolerance`` (rad or m) of a limit is on it, and ``horizon`` (m of
    object travel; 0: on-limit rows only) is Problem 2's travel horizon."""

    tolerance: float = DEFAULT_TOLERANCE
    horizon: float = DEFAULT_HORIZON


def check_joint_limits(c: Checker, value: Any) -> dict[str, float] | bool:
    """``joint_limits``: ``false`` (the paper's LPs, no position limits) or a table of
    ``tolerance`` and ``horizon`` (``docs/joint-limits.md``), completed with the defaults
    ([`limit_options()`][mjtvm.grasp.resolve.state.limit_options] reads it)."""
    if value is False:
        return False
    if not isinstance(value, Mapping):
        raise c.fail(
            "joint_limits", f"expected false or a table of tolerance and horizon, got {kind_of(value)}"
        )
    for key in sorted(set(value) - {"tolerance", "horizon"}):
        raise c.fail(f"joint_limits.{key}", "unknown key (allowed: horizon, tolerance)")
    default = JointLimitOptions()
    return {
        k: c.number(value[k], f"joint_limits.{k}", low=0.0) if k in value else float(getattr(default, k))
        for k in ("tolerance", "horizon")
    }
