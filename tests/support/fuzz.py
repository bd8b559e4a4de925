r"""Mutations of ``mjtvm.state/1`` documents, for robustness tests of the loader.

Used by ``tests/problem2/test_fuzz.py`` (driven by hypothesis) and ``tools/fuzz_states.py``
(at scale). Every mutation takes a :class:`random.Random`, so one seed replays one
mutated document exactly. The contract they test: :func:`mjtvm.load_state` raises
nothing but :class:`~mjtvm.errors.MjtvmError` (a :class:`~mjtvm.errors.StateError`
naming the field), and a state that loads is solved by :func:`mjtvm.problem2.tvmmp` with only
package errors and JSON-clean (finite) output.
"""

from __future__ import annotations

import copy
import json
import random
from collections.abc import Callable
from typing import Any

from mjtvm.model.bounds import (
    MAX_ABS,
    MAX_CONTACTS,
    MAX_FRICTION_EDGES,
    MAX_JOINTS,
    MAX_RANGE_VERTICES,
    MAX_REFS,
)

__all__ = ["NASTY_VALUES", "mutate_bytes", "mutate_document", "nested"]

Path = tuple[Any, ...]


def nested(depth: int, leaf: Any = 0.0) -> Any:
    """A value nested ``depth`` lists deep (built iteratively: ``depth`` may be 10**5)."""
    out = leaf
    for _ in range(depth):
        out = [out]
    return out


# Values that broke the loader once, or sit on a bound: huge, tiny, non-finite, integers
# beyond a float, wrong types. Each is used as a replacement for any node of a document.
NASTY_VALUES: tuple[Any, ...] = (
    0, -1, 1, 2, 3, 1.5, 16.0, 16.5, -0.0, 1e-12, 5e-324, 1e-300, -1e-300,
    MAX_ABS, -MAX_ABS, MAX_ABS * 1.000001, 1e13, 1e20, 1e30, 1e154, -1e154, 1e300, 1e308, -1e308,
    float("nan"), float("inf"), float("-inf"),
    2**53 + 1, 2**63, -(2**64), 2**1023, 2**1024, 2**1100, 10**400, 10**12, 10**6,
    MAX_FRICTION_EDGES, MAX_FRICTION_EDGES + 1,
    "", "1.5", "nan", "F", "S", "x" * 300, "\ud800", "mjtvm.state/1",
    True, False, None,
    {}, {"a": 1}, {"0": 0.0}, [], [[]], [0.0], [1, 2], [[0.0, 0.0]], ["a", "b"], [None], [True, 1.0],
)  # fmt: skip  # a table: one row per kind of value (text, booleans and null, containers)


# Values of the top-level slots that have their own rules (bounds, enumerations).
SPECIALS: dict[str, list[Any]] = {
    "friction_edges": [10**12, 1e30, 10**6, 16.0, 16.5, 2, 3, 256, 257, "16", True, -16],
    "space": [2, 3, 3.0, 2.5, 1, "3", True, None],
    "slip": ["shared", "per_contact", "", None, 1, ["shared"]],
    "schema": ["mjtvm.state/2", "", None, 1],
    "refs": [[[0, 0, -1e12, 0, 0, 0]], [[0, 0, 1e-12, 0, 0, 0]], [[0] * 6], [[0] * 3], []],
    "rvds": [[[1e12, 0, 0, 0, 0, 0]], [[0] * 6], [[-1e308, 0, 0, 0, 0, 0]], [], None],
}


def _paths(doc: Any) -> list[Path]:
    """Every node's path (the root excluded), iteratively."""
    out: list[Path] = []
    stack: list[tuple[Any, Path]] = [(doc, ())]
    while stack:
        node, path = stack.pop()
        if path:
            out.append(path)
        if isinstance(node, dict):
            stack.extend((v, (*path, k)) for k, v in node.items())
        elif isinstance(node, list):
            stack.extend((v, (*path, i)) for i, v in enumerate(node))
    return out


def _get(doc: Any, path: Path) -> Any:
    for key in path:
        doc = doc[key]
    return doc


def _set(doc: Any, path: Path, value: Any) -> None:
    _get(doc, path[:-1])[path[-1]] = value


def _numbers(node: Any, f: Callable[[float], Any]) -> Any:
    if isinstance(node, list):
        return [_numbers(x, f) for x in node]
    if isinstance(node, dict):
        return {k: _numbers(v, f) for k, v in node.items()}
    if isinstance(node, (int, float)) and not isinstance(node, bool):
        try:
            return f(node)
        except OverflowError:  # an integer beyond a float (an earlier mutation): keep it
            return node
    return node


def _grow(node: list[Any], rng: random.Random, path: Path) -> list[Any]:
    # Mostly a few more entries; sometimes exactly past a size bound, so that the bound's
    # message is exercised without the fuzz solving 256 x 256 LPs.
    if not node:
        return [rng.choice(NASTY_VALUES)]
    bounds = {"joints": MAX_JOINTS, "contacts": MAX_CONTACTS, "refs": MAX_REFS, "rvds": MAX_REFS}
    bound = bounds.get(path[-1]) if path and isinstance(path[-1], str) else None
    if path and path[-1] == "operation_range":
        bound = MAX_RANGE_VERTICES
    if bound is not None and rng.random() < 0.3:
        return [copy.deepcopy(rng.choice(node)) for _ in range(bound + 1)]
    return node + [copy.deepcopy(rng.choice(node)) for _ in range(rng.randint(1, 3))]


def _mutate_once(doc: Any, rng: random.Random) -> tuple[Any, bool]:
    """One mutation in place; the flag says the result is too deep to mutate further."""
    paths = _paths(doc)
    kind = rng.randrange(12)
    if kind == 0 or not paths:  # the root itself
        root = [[], "state", 1.0, None, nested(rng.choice([10, 2000])), {"schema": "mjtvm.state/1"}]
        return rng.choice(root), True
    path = rng.choice(paths)
    node = _get(doc, path)
    parent = _get(doc, path[:-1])
    if kind in (1, 2, 3):  # replace any node with a nasty value
        _set(doc, path, copy.deepcopy(rng.choice(NASTY_VALUES)))
    elif kind == 4:  # delete a key or a list entry
        del parent[path[-1]]
    elif kind == 5:  # add a key (unknown, or a known one in the wrong place)
        target = parent if isinstance(parent, dict) else doc
        key = rng.choice(["frobnicate", "mu", "tangent", "slide_direction", "rvds", "slip", "friction_edges"])
        target[key] = copy.deepcopy(rng.choice(NASTY_VALUES))
    elif kind == 6:  # deep nesting in place of a node (copy and recursion stop here)
        depth = rng.choice([3, 9, 50, 1200, 5000])
        _set(doc, path, nested(depth, node))
        return doc, depth > 9
    elif kind == 7 and isinstance(node, list):  # truncate or grow a list
        _set(
            doc, path, node[: rng.randrange(len(node) + 1)] if rng.random() < 0.5 else _grow(node, rng, path)
        )
    elif kind == 8:  # swap a type: list <-> object, number -> string/list
        if isinstance(node, list):
            swapped: Any = {str(i): v for i, v in enumerate(node)}
        elif isinstance(node, dict):
            swapped = list(node.values())
        elif isinstance(node, (int, float)) and not isinstance(node, bool):
            swapped = rng.choice([str(node), [node], {"value": node}, bool(node)])
        else:
            swapped = rng.choice([0.0, [node], None])
        _set(doc, path, swapped)
    elif kind == 9:  # scale a numeric subtree by a power of ten (units, overflow, underflow)
        factor = 10.0 ** rng.choice([-300, -160, -20, -12, -6, -1, 1, 6, 9, 12, 13, 20, 154, 300])
        _set(doc, path, _numbers(node, lambda x: x * factor))
    elif kind == 10:  # nudge numbers (unit normals, on-axis vertices, convexity)
        eps = rng.choice([1e-12, 1e-9, 1e-7, 1e-5, 1e-3, -1e-7, -1e-3])
        _set(doc, path, _numbers(node, lambda x: x * (1 + eps) + eps))
    else:  # a special value in a top-level slot with its own rules
        key = rng.choice(sorted(SPECIALS))
        doc[key] = copy.deepcopy(rng.choice(SPECIALS[key]))
    return doc, False


def mutate_document(doc: dict[str, Any], rng: random.Random) -> Any:
    """A deep copy of ``doc`` with one to three random mutations (see the module docstring)."""
    out: Any = copy.deepcopy(doc)
    for _ in range(rng.choice([1, 1, 1, 2, 3])):
        out, final = _mutate_once(out, rng)
        if final or not isinstance(out, (dict, list)):
            break
    return out


def mutate_bytes(doc: dict[str, Any], rng: random.Random) -> bytes:
    """The JSON bytes of ``doc``, damaged: truncated, invalid UTF-8, a BOM, deep brackets..."""
    raw = json.dumps(doc, indent=rng.choice([None, 1])).encode()
    kind = rng.randrange(8)
    pos = rng.randrange(len(raw) + 1)
    if kind == 0:  # truncated
        return raw[:pos]
    if kind == 1:  # invalid UTF-8 inside (or outside) a string
        return (
            raw[:pos]
            + rng.choice([b"\xff", b"\xc3\x28", b"\xed\xa0\x80", b"\x80", b"\xf8\x88\x80\x80\x80"])
            + raw[pos:]
        )
    if kind == 2:  # a byte overwritten
        return raw[:pos] + bytes([rng.randrange(256)]) + raw[pos + 1 :]
    if kind == 3:  # other encodings
        return rng.choice(
            [b"\xef\xbb\xbf" + raw, raw.decode().encode("utf-16"), raw.decode().encode("latin-1") + b"\xe9"]
        )
    if kind == 4:  # deep brackets
        depth = rng.choice([100, 999, 1001, 100_000])
        return b"[" * depth + b"]" * depth if rng.random() < 0.5 else b'{"a":' * depth + b"0" + b"}" * depth
    if kind == 5:  # number literals a float cannot hold, or too many digits for an int
        lit = rng.choice([b"1e400", b"-1e400", b"1" * 400, b"9" * 5000, b"NaN", b"-Infinity", b"1.5e-400"])
        return raw.replace(b"0.3", lit, 1) if b"0.3" in raw else raw.replace(b"16", lit, 1)
    if kind == 6:  # a repeated key
        return raw.replace(b'"space": 3', b'"space": 3, "space": 2', 1)
    return rng.choice([b"", b"null", b"[]", b"{}", b"\x00" * 64, b'"state"'])
