r"""Bounds of the ``mjtvm.state/1`` format and the number checks shared by its validators.

Every number of a state is finite and at most [`MAX_ABS`][mjtvm.model.bounds.MAX_ABS] in absolute value, and
every list has a bounded length (the constants below; ``docs/state-format.md`` gives
the reasons). [`float_array()`][mjtvm.model.bounds.float_array] turns a nested list (or an array) into a float array
only after checking every leaf, so that a string, a boolean, an object or an integer
too large for a float is reported as one [`StateError`][mjtvm.errors.StateError] naming the
field, never as a ``TypeError``/``OverflowError`` deep inside numpy, and never silently
converted (numpy would turn ``"1.5"`` and ``true`` into numbers).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mjtvm.errors import StateError

__all__ = [
    "MAX_ABS",
    "MAX_CONTACTS",
    "MAX_DEPTH",
    "MAX_FILE_BYTES",
    "MAX_FRICTION_EDGES",
    "MAX_JOINTS",
    "MAX_NAME",
    "MAX_RANGE_VERTICES",
    "MAX_REFS",
    "MAX_RVDS",
    "MIN_FRICTION_EDGES",
    "check_json_tree",
    "checked_name",
    "describe",
    "float_array",
    "integer",
    "number",
]

# Every number of a state: SI values of a hand are many orders below, and the LPs'
# tolerances (1e-9 relative) cannot resolve a state that spans more than ~1e21.
MAX_ABS = 1e12
MAX_JOINTS = 128  # two human hands have ~50; bench_suite scales to 16 fingers x 4 joints
MAX_CONTACTS = 128
MAX_REFS = 256  # Problem 2 solves one LP per (REFS, RVDS) pair: 256 x 256 at most
MAX_RVDS = 256
MAX_RANGE_VERTICES = 256  # a digitised motor curve; a datasheet gives 4 or 5
MIN_FRICTION_EDGES = 3  # the fewest edges that span a pyramid
MAX_FRICTION_EDGES = 256  # inscribed-pyramid error 1 - cos(pi / 256) < 1e-4; LP size grows linearly
MAX_NAME = 256  # characters of a joint or contact name
MAX_DEPTH = 8  # the deepest valid value (contacts[i].jacobian[r][c]) sits at depth 5
MAX_FILE_BYTES = 64 * 2**20  # a state at every size bound above, indented, is ~20 MiB


def describe(value: Any) -> str:
    """A short description of a value for an error message (never the whole value)."""
    if isinstance(value, bool) or value is None:
        return "true" if value is True else "false" if value is False else "null"
    if isinstance(value, int):
        text = str(value) if abs(value) < 10**20 else f"an integer of {len(str(abs(value)))} digits"
        return text
    if isinstance(value, float):
        return repr(value)
    if isinstance(value, str):
        return f"the string {value[:40]!r}" + ("..." if len(value) > 40 else "")
    if isinstance(value, Mapping):
        return "an object"
    if isinstance(value, (list, tuple)):
        return f"a list of {len(value)}"
    return type(value).__name__


def _at(index: tuple[int, ...]) -> str:
    return " at " + "".join(f"[{i}]" for i in index) if index else ""


def number(value: Any, field: str, *, index: tuple[int, ...] = ()) -> float:
    """Check one number: int or float (not bool), finite, ``|x| <= MAX_ABS``; return it as float.

    The magnitude is compared before any conversion: ``int(10**400)`` does not fit a float.
    """
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise StateError(field, f"expected a number, got {describe(value)}{_at(index)}", value)
    if isinstance(value, (float, np.floating)) and not math.isfinite(value):
        raise StateError(
            field, f"expected finite numbers (no NaN or infinity), got {value!r}{_at(index)}", value
        )
    if abs(value) > MAX_ABS:
        raise StateError(
            field,
            f"expected |x| <= {MAX_ABS:g} (the format's bound), got {describe(value)}{_at(index)}",
            value,
        )
    return float(value)


def integer(value: Any, field: str, lo: int, hi: int) -> int:
    """Check an integer in ``[lo, hi]``; an integral float (JSON ``16.0``) counts as one."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise StateError(field, f"expected an integer in [{lo}, {hi}], got {describe(value)}", value)
    if isinstance(value, (float, np.floating)) and not (math.isfinite(value) and float(value).is_integer()):
        raise StateError(field, f"expected an integer in [{lo}, {hi}], got {describe(value)}", value)
    if not lo <= value <= hi:
        raise StateError(field, f"expected an integer in [{lo}, {hi}], got {describe(value)}", value)
    return int(value)


def checked_name(value: Any, field: str) -> str:
    """A joint's or contact's name, checked.

    Parameters
    ----------
    value
        The name as read (any JSON value).
    field
        The field it came from, for the error (``joints[0].name``).

    Returns
    -------
    str
        ``value``: a non-empty string of at most [`MAX_NAME`][mjtvm.model.bounds.MAX_NAME]
        characters that encodes as UTF-8.

    Raises
    ------
    StateError
        Naming ``field`` when ``value`` is not such a string.
    """
    if not isinstance(value, str) or not value:
        raise StateError(field, f"expected a non-empty string, got {describe(value)}", value)
    if len(value) > MAX_NAME:
        raise StateError(field, f"expected at most {MAX_NAME} characters, got {len(value)}", value)
    try:
        value.encode("utf-8")
    except UnicodeEncodeError as e:  # a lone surrogate from a JSON escape such as "\ud800"
        raise StateError(field, "expected valid Unicode text (no lone surrogates)", value) from e
    return value


def float_array(
    value: Any,
    field: str,
    *,
    ndim: int,
    max_len: int | None = None,
    max_width: int | None = None,
    what: str = "numbers",
) -> NDArray[np.float64]:
    r"""A read-only float array of ``ndim`` dimensions from nested lists (or an array).

    Every leaf is checked by [`number()`][mjtvm.model.bounds.number], and every level must be a list (rows of
    equal length). Shapes beyond the nesting (lengths, columns) are the caller's.

    Parameters
    ----------
    value
        Nested lists, tuples or a numeric array.
    field
        The field path for errors.
    ndim
        1 (a vector) or 2 (a list of rows).
    max_len
        Largest allowed length of the outer list (the bound is put in the message).
    max_width
        Largest allowed length of each row (``ndim == 2``).
    what
        What the value is, for the messages (``"a list of [torque, speed] pairs"``).
    """
    if isinstance(value, np.ndarray):
        if value.dtype.kind not in "iuf":
            raise StateError(field, f"expected {what}, got an array of {value.dtype}", None)
        if value.ndim != ndim:
            raise StateError(field, f"expected {what}, got an array of shape {value.shape}", None)
        if _plain_floats(value, ndim, max_len, max_width):  # what the checks below pass, at once
            out = np.array(value, dtype=float, order="C")  # row-major as the lists give it
            out.setflags(write=False)
            return out
        value = value.tolist()  # exact for int and float arrays; the leaves are checked below
    if not isinstance(value, (list, tuple)):
        raise StateError(field, f"expected {what}, got {describe(value)}", value)
    if max_len is not None and len(value) > max_len:
        raise StateError(field, f"expected at most {max_len} entries, got {len(value)}", None)
    if ndim == 1:
        out = np.array([number(x, field, index=(i,)) for i, x in enumerate(value)], dtype=float)
    else:
        width = None
        rows = []
        for i, row in enumerate(value):
            if isinstance(row, np.ndarray):
                row = row.tolist()
            if not isinstance(row, (list, tuple)):
                raise StateError(field, f"expected {what}, got {describe(row)} at [{i}]", value)
            if width is None:
                width = len(row)
                if max_width is not None and width > max_width:
                    raise StateError(
                        field, f"expected rows of at most {max_width} entries, got {width}", None
                    )
            elif len(row) != width:
                raise StateError(
                    field, f"expected rows of equal length, got {width} and {len(row)} at [{i}]", None
                )
            rows.append([number(x, field, index=(i, j)) for j, x in enumerate(row)])
        out = np.array(rows, dtype=float).reshape(len(rows), width or 0)
    out.setflags(write=False)
    return out


def _plain_floats(value: NDArray[Any], ndim: int, max_len: int | None, max_width: int | None) -> bool:
    """A float array of ``ndim`` dimensions that `float_array()`'s checks pass: finite, every
    ``|x| <= MAX_ABS``, within ``max_len`` and ``max_width``, and not an empty list of rows
    (which the checks give the shape ``(0, 0)``)."""
    if value.dtype.kind != "f" or value.ndim != ndim or (ndim == 2 and value.shape[0] == 0):
        return False
    if max_len is not None and value.shape[0] > max_len:
        return False
    if ndim == 2 and max_width is not None and value.shape[1] > max_width:
        return False
    # one pass: a NaN or an infinity fails |x| <= MAX_ABS (finite) as np.isfinite would
    return bool((np.abs(value) <= MAX_ABS).all())


def check_json_tree(data: Any, field: str = "") -> None:
    """Check that a decoded document is plain JSON no deeper than [`MAX_DEPTH`][mjtvm.model.bounds.MAX_DEPTH].

    Iterative (an explicit stack), so that a document nested thousands deep or a mapping
    that contains itself is refused with a [`StateError`][mjtvm.errors.StateError] rather than a
    ``RecursionError``. Allowed values: mappings with string keys, lists and tuples,
    strings, numbers, booleans, ``None`` and numeric numpy arrays or scalars (a mapping
    built in Python); which of them fits where is checked by the field validators.
    """
    # Paths are kept as (parent, key) links and spelled out only for an error.
    stack: list[tuple[Any, Any, int]] = [(data, None, 0)]
    while stack:
        node, link, depth = stack.pop()
        if depth > MAX_DEPTH:
            raise StateError(
                _path(field, link), f"nested deeper than {MAX_DEPTH} levels (a state needs at most 5)"
            )
        if isinstance(node, Mapping):
            for key, child in node.items():
                if not isinstance(key, str):
                    raise StateError(
                        _path(field, link), f"expected string keys in a JSON object, got {describe(key)}"
                    )
                stack.append((child, (link, key), depth + 1))
        elif isinstance(node, (list, tuple)):
            stack.extend((child, (link, i), depth + 1) for i, child in enumerate(node))
        elif isinstance(node, np.ndarray):
            if node.dtype.kind not in "iufb" or node.ndim + depth > MAX_DEPTH:
                raise StateError(
                    _path(field, link), f"expected a numeric array, got {node.dtype} of shape {node.shape}"
                )
        elif node is not None and not isinstance(node, (str, int, float, np.generic)):
            raise StateError(_path(field, link), f"expected a JSON value, got {type(node).__name__}")


def _path(field: str, link: Any) -> str:
    keys = []
    while link is not None:
        link, key = link
        keys.append(key)
    out = field
    for key in reversed(keys):
        out += f"[{key}]" if isinstance(key, int) else (f".{key}" if out else key)
    return out
