"""The value types of the options (argparse ``type=``) and the range of each option, in one
place: one-line errors naming what is expected. Every type with a range says what it accepts
in its ``accepted`` attribute ([`accepted()`][mjtvm.cli.values.accepted]): ``--help`` shows it,
and ``docs/cli.md``'s "Bounds" table is generated from it (``tools/cli_tables.py``)."""

from __future__ import annotations

import argparse
import math
import os
import re
import stat
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any, TypeVar

__all__ = [
    "CONTACTS",
    "MAX_BASELINE_REPEATS",
    "MAX_FORCE",
    "MAX_GEAR",
    "MAX_GRID",
    "MAX_INDENT",
    "MAX_JOBS",
    "MAX_LAUNCH",
    "MAX_LIST",
    "MAX_MEMORY",
    "MAX_MU",
    "MAX_NOTES_BYTES",
    "MAX_REPEATS",
    "MAX_SCALE",
    "MAX_SECONDS",
    "MAX_SIM_SECONDS",
    "MAX_STATES",
    "MAX_STEM",
    "MIN_GEAR",
    "NAME_MAX",
    "PATH_MAX",
    "READINGS",
    "accepted",
    "choices",
    "cluster_address",
    "folder",
    "fraction",
    "grasps",
    "input_file",
    "input_path",
    "integer",
    "integers",
    "memory_size",
    "names",
    "number",
    "numbers",
    "output_file",
    "shown",
    "source",
    "stem",
]

CONTACTS = ("L", "S")
READINGS = ("physical", "literal")

# The accepted range of every option (docs/cli.md, "Bounds"). An upper bound keeps a typo
# (an extra zero, a pasted number) from becoming a run of days or a MemoryError.
MAX_INDENT = 16  # JSON indentation: json.dumps builds every line's prefix in memory
MAX_STATES = 10_000  # states along a lift (the paper's figures use 30); also --stride, --tvms-every
MAX_JOBS = 64  # worker processes, each with its own MuJoCo and HiGHS (100-200 MB)
MAX_REPEATS = 100_000  # bench: timed Problem 2 calls per state (about a millisecond each)
MAX_BASELINE_REPEATS = 1_000  # bench: timed cvxpy calls per state (about 0.1 s each)
MAX_SECONDS = 86_400.0  # --time-limit: a day
MAX_MU = 100.0  # a friction coefficient (rubber on rubber is about 1-2)
MAX_FORCE = 1e6  # N: --mg, --preload
MIN_GEAR, MAX_GEAR = (
    1.0,
    10_000.0,
)  # --gears: a reduction (a tiny ratio scales the torques past the state bounds)
MAX_SCALE = 1_000.0  # verify --armature-scale
MAX_LAUNCH = 1.0  # m: verify --launch, the stated distance of a launch from rest
MAX_SIM_SECONDS = 1.0  # verify --window, --startup: 4000 MuJoCo steps of 0.25 ms per rollout
MAX_MEMORY = 2**50  # --memory: 1 PiB
MAX_LIST = 1_000  # entries of one comma-separated list
MAX_GRID = 100_000  # sweep: points of the product of its lists (a row is kept in memory for each)
NAME_MAX = 255  # bytes of one path component (Linux NAME_MAX)
PATH_MAX = 4095  # bytes of a path (Linux PATH_MAX, less the terminating NUL)
MAX_STEM = 200  # characters of --name: NAME.partial.json's temporary file must fit NAME_MAX
MAX_NOTES_BYTES = 2**20  # bench --notes: read at most this much


_F = TypeVar("_F", bound=Callable[..., Any])


def _accepting(parse: _F, text: str) -> _F:
    """``parse``, saying in ``parse.accepted`` what it accepts (``--help``, docs/cli.md's "Bounds")."""
    parse.accepted = text  # type: ignore[attr-defined]
    return parse


def accepted(type_: object) -> str | None:
    """What an option's type accepts, as ``--help`` and docs/cli.md's "Bounds" say it (backticks:
    literals), or None for a type without a range (a path, a choice, a name)."""
    text = getattr(type_, "accepted", None)
    return text if isinstance(text, str) else None


def shown(text: str, limit: int = 60) -> str:
    """``text`` for a one-line message: ``repr`` (a newline or a lone surrogate stays escaped),
    cut to ``limit`` characters."""
    return repr(text[:limit]) + ("..." if len(text) > limit else "")


def _bound(x: float) -> str:
    return str(int(x)) if float(x).is_integer() and abs(x) < 1e15 else f"{x:g}"  # 1000000, not 1e+06


def _interval(low: float, high: float, *, strict: bool = False) -> str:
    return f"{'(' if strict else '['}{_bound(low)}, {_bound(high)}]"


def integer(low: int, high: int, *, hint: str = "") -> Callable[[str], int]:
    """An argparse type: an integer in ``[low, high]`` (``1.5``, ``nan`` and ``0,3`` are errors)."""

    def parse(text: str) -> int:
        try:
            value = int(text.strip(), 10)
        except ValueError:  # also more than 4300 digits (int_max_str_digits)
            value = None
        if value is None or not low <= value <= high:
            extra = f" ({hint})" if hint and "," in text else ""
            raise argparse.ArgumentTypeError(
                f"expected an integer in {_interval(low, high)}, got {shown(text)}{extra}"
            )
        return value

    return _accepting(parse, f"integer in {_interval(low, high)}")


def _float(text: str) -> float | None:
    try:
        value = float(text)
    except ValueError:
        return None
    return value if math.isfinite(value) else None


def number(low: float, high: float, *, strict: bool = False, unit: str = "number") -> Callable[[str], float]:
    """An argparse type: a finite number in ``[low, high]``, or ``(low, high]`` when ``strict``
    (``unit``: what it accepts, ``"seconds"``, ``"N"``, ...)."""

    def parse(text: str) -> float:
        value = _float(text)
        if value is None or not (low < value if strict else low <= value) or value > high:
            raise argparse.ArgumentTypeError(
                f"expected a number in {_interval(low, high, strict=strict)}, got {shown(text)}"
            )
        return value

    return _accepting(parse, f"{unit} in {_interval(low, high, strict=strict)}")


def fraction(text: str) -> float:
    """An argparse type: a number in [0, 1) (a relative tolerance, a probability, a margin)."""
    value = _float(text)
    if value is None or not 0.0 <= value < 1.0:
        raise argparse.ArgumentTypeError(f"expected a number in [0, 1), got {shown(text)}")
    return value


fraction.accepted = "number in [0, 1)"  # type: ignore[attr-defined]


_UNITS = {"": 1, "K": 2**10, "M": 2**20, "G": 2**30, "T": 2**40}


def memory_size(text: str) -> int:
    """An argparse type: bytes as ``512M``, ``2G``, ``1.5GiB``, ``2000000000`` or a share of the
    available memory, ``25%``; at most [`MAX_MEMORY`][mjtvm.cli.values.MAX_MEMORY]."""
    t = text.strip().upper().removesuffix("IB").removesuffix("B")
    try:
        if t.endswith("%"):
            share = float(t[:-1])
            if not 0.0 < share <= 100.0:
                raise ValueError
            from mjtvm.polytopes.budget import available_memory

            value = share / 100.0 * available_memory()
        else:
            unit = t[-1:] if t[-1:] in _UNITS and t[-1:] != "" else ""
            value = float(t[: len(t) - len(unit)]) * _UNITS[unit]
        if not (math.isfinite(value) and 1.0 <= value <= MAX_MEMORY):
            raise ValueError
        return int(value)
    except (ValueError, IndexError):
        raise argparse.ArgumentTypeError(
            "expected a size such as 512M, 2G or 25% (of the available memory), at most 1024T, "
            f"got {shown(text)}"
        ) from None


memory_size.accepted = (  # type: ignore[attr-defined]
    f"1 byte to {MAX_MEMORY // _UNITS['T']}T, or a share in (0, 100] % of the available memory"
)


def _items(text: str, what: str) -> list[str]:
    values = text.split(",")
    if len(values) > MAX_LIST:
        raise argparse.ArgumentTypeError(
            f"expected at most {MAX_LIST} comma-separated {what}, got {len(values)}"
        )
    return values


def numbers(
    low: float, high: float, *, strict: bool = False, unit: str = "numbers"
) -> Callable[[str], tuple[float, ...]]:
    """An argparse type: at most [`MAX_LIST`][mjtvm.cli.values.MAX_LIST] comma-separated finite numbers in ``[low, high]``
    (``(low, high]`` when ``strict``; ``unit``: what they are, as [`number()`][mjtvm.cli.values.number] has it)."""
    one = number(low, high, strict=strict)

    def parse(text: str) -> tuple[float, ...]:
        try:
            return tuple(one(v) for v in _items(text, "numbers"))
        except argparse.ArgumentTypeError as e:
            if str(e).startswith("expected at most"):
                raise
            raise argparse.ArgumentTypeError(
                f"expected comma-separated numbers in {_interval(low, high, strict=strict)}, got {shown(text)}"
            ) from None

    return _accepting(
        parse, f"comma-separated {unit} in {_interval(low, high, strict=strict)}, at most {MAX_LIST}"
    )


def integers(low: int, high: int) -> Callable[[str], tuple[int, ...]]:
    """An argparse type: at most [`MAX_LIST`][mjtvm.cli.values.MAX_LIST] comma-separated integers in ``[low, high]``."""
    one = integer(low, high)

    def parse(text: str) -> tuple[int, ...]:
        try:
            return tuple(one(v) for v in _items(text, "integers"))
        except argparse.ArgumentTypeError as e:
            if str(e).startswith("expected at most"):
                raise
            raise argparse.ArgumentTypeError(
                f"expected comma-separated integers in {_interval(low, high)}, got {shown(text)}"
            ) from None

    return _accepting(parse, f"comma-separated integers in {_interval(low, high)}, at most {MAX_LIST}")


def choices(allowed: Sequence[str], *, every: str | None = None) -> Callable[[str], tuple[str, ...]]:
    """An argparse type: distinct comma-separated values of ``allowed`` (``every``: all of them)."""
    expected = ",".join(allowed) + (f" or {every}" if every else "")

    def parse(text: str) -> tuple[str, ...]:
        if every is not None and text.strip() == every:
            return tuple(allowed)
        values = tuple(v.strip() for v in text.split(","))
        if not text.strip() or len(set(values)) != len(values) or any(v not in allowed for v in values):
            raise argparse.ArgumentTypeError(f"expected distinct values among {expected}, got {shown(text)}")
        return values

    return parse


def names(text: str) -> tuple[str, ...]:
    """An argparse type: at most [`MAX_LIST`][mjtvm.cli.values.MAX_LIST] non-empty comma-separated names."""
    values = tuple(v.strip() for v in _items(text, "names"))
    if not all(values):
        raise argparse.ArgumentTypeError(f"expected comma-separated names, got {shown(text)}")
    return values


names.accepted = f"comma-separated names, at most {MAX_LIST}"  # type: ignore[attr-defined]


_STEM = re.compile(r"[A-Za-z0-9_][A-Za-z0-9_.-]*")


def stem(text: str) -> str:
    """An argparse type: a file stem (letters, digits, ``_ . -``; no folder, no leading dot), at
    most [`MAX_STEM`][mjtvm.cli.values.MAX_STEM] characters."""
    if not _STEM.fullmatch(text) or len(text) > MAX_STEM:
        raise argparse.ArgumentTypeError(
            f"expected a file stem of 1 to {MAX_STEM} letters, digits, '_', '.', '-' (no '/'), got {shown(text)}"
        )
    return text


stem.accepted = (  # type: ignore[attr-defined]
    f"1 to {MAX_STEM} letters, digits, `_ . -` (no `/`; its files and their temporary files "
    "must fit a file name)"
)


# ------------------------------------------------------------------ paths
def _path(text: str, what: str) -> Path:
    """``text`` as a path the system can take: not empty, at most [`PATH_MAX`][mjtvm.cli.values.PATH_MAX] bytes, no
    component over [`NAME_MAX`][mjtvm.cli.values.NAME_MAX] bytes (else ``stat`` fails with ENAMETOOLONG deep inside)."""
    if not text:
        raise argparse.ArgumentTypeError(f"expected {what}, got ''")
    try:
        raw = os.fsencode(text)  # undecodable bytes of argv come back as they were given
    except UnicodeError:
        raise argparse.ArgumentTypeError(f"expected {what}, got the unencodable {shown(text)}") from None
    if len(raw) > PATH_MAX:
        raise argparse.ArgumentTypeError(f"expected {what} of at most {PATH_MAX} bytes, got {len(raw)} bytes")
    longest = max(raw.split(b"/"), key=len)
    if len(longest) > NAME_MAX:
        raise argparse.ArgumentTypeError(
            f"expected {what} whose every component has at most {NAME_MAX} bytes, got one of "
            f"{len(longest)} bytes: {shown(os.fsdecode(longest), 40)}"
        )
    return Path(text)


def _is_dir(path: Path, what: str) -> bool:
    """Whether ``path`` is a folder; a path that cannot be inspected is a one-line error."""
    try:
        return stat.S_ISDIR(path.stat().st_mode)
    except (FileNotFoundError, NotADirectoryError):
        return False
    except OSError as e:
        raise argparse.ArgumentTypeError(
            f"expected {what}, cannot inspect {shown(str(path))} ({e.strerror or e})"
        ) from None


def folder(text: str) -> str:
    """An argparse type: an output folder (a ``.json``/``.csv``/``.md`` file name is refused: the files are written inside it)."""
    if not text.strip():
        raise argparse.ArgumentTypeError("expected a folder, got ''")
    path = _path(text, "a folder")
    if path.suffix in (".json", ".csv", ".md") and not _is_dir(path, "a folder"):
        raise argparse.ArgumentTypeError(
            f"expected a folder (the output files are written inside it), got the file name {shown(text)}"
        )
    return text


def output_file(text: str) -> str:
    """An argparse type: a file to write (not a folder; its folder is checked before any work)."""
    path = _path(text, "a file name")
    if _is_dir(path, "a file name"):
        raise argparse.ArgumentTypeError(f"expected a file name, got the folder {shown(text)}")
    if text.endswith(("/", os.sep)):  # a folder's name, existing or not (Path() drops the slash)
        raise argparse.ArgumentTypeError(f"expected a file name, got the folder name {shown(text)}")
    return text


def input_file(text: str) -> Path:
    """An argparse type: an existing file to read (not a folder)."""
    path = _path(text, "a file")
    if _is_dir(path, "a file"):
        raise argparse.ArgumentTypeError(f"expected a file, got the folder {shown(text)}")
    if not os.path.lexists(path):
        raise argparse.ArgumentTypeError(f"expected an existing file, got {shown(text)}")
    return path


def input_path(text: str) -> Path:
    """An argparse type: an existing file or folder to read."""
    path = _path(text, "a file or folder")
    if not os.path.lexists(path):
        raise argparse.ArgumentTypeError(f"expected an existing file or folder, got {shown(text)}")
    return path


def source(text: str) -> str:
    """An argparse type: a state or grasp file, ``-``, or a shipped grasp's name (a path the
    system can take; whether it exists is the loader's to say, naming the shipped grasps)."""
    if text != "-":
        _path(text, "a file or a shipped grasp's name")
    return text


def grasps(text: str) -> tuple[str, ...]:
    """An argparse type: comma-separated grasps (each as [`source()`][mjtvm.cli.values.source])."""
    values = names(text)
    for value in values:
        source(value)
    return values


grasps.accepted = f"comma-separated grasps, at most {MAX_LIST}"  # type: ignore[attr-defined]


_CLUSTER = re.compile(r"(?:(tcp|tls|ucx|ws|wss)://)?\[?[A-Za-z0-9_.:-]+\]?:\d{1,5}")


def cluster_address(text: str) -> str:
    """An argparse type: a Dask scheduler address ``[tcp://]HOST:PORT``."""
    if not _CLUSTER.fullmatch(text.strip()) or not 0 < int(text.rsplit(":", 1)[1]) < 65536:
        raise argparse.ArgumentTypeError(f"expected a scheduler address tcp://HOST:PORT, got {text!r}")
    return text.strip()
