"""The value types of the options (argparse ``type=``): one-line errors naming what is expected."""

from __future__ import annotations

import argparse
import math
import re
from collections.abc import Callable, Sequence
from pathlib import Path

__all__ = [
    "CONTACTS",
    "READINGS",
    "choices",
    "cluster_address",
    "folder",
    "fraction",
    "integer",
    "integers",
    "memory_size",
    "names",
    "number",
    "numbers",
    "stem",
]

CONTACTS = ("L", "S")
READINGS = ("physical", "literal")


def integer(low: int, *, hint: str = "") -> Callable[[str], int]:
    """An argparse type: an integer >= ``low`` (``1.5``, ``nan`` and ``0,3`` are errors)."""

    def parse(text: str) -> int:
        try:
            value = int(text.strip(), 10)
        except ValueError:
            value = None
        if value is None or value < low:
            extra = f" ({hint})" if hint and "," in text else ""
            raise argparse.ArgumentTypeError(f"expected an integer >= {low}, got {text!r}{extra}")
        return value

    return parse


def _float(text: str) -> float | None:
    try:
        value = float(text)
    except ValueError:
        return None
    return value if math.isfinite(value) else None


def number(low: float | None = None, *, strict: bool = False) -> Callable[[str], float]:
    """An argparse type: a finite number, ``> low`` (``strict``) or ``>= low``."""
    bound = "" if low is None else f" {'>' if strict else '>='} {low:g}"

    def parse(text: str) -> float:
        value = _float(text)
        if value is None or (low is not None and (value <= low if strict else value < low)):
            raise argparse.ArgumentTypeError(f"expected a finite number{bound}, got {text!r}")
        return value

    return parse


def fraction(text: str) -> float:
    """An argparse type: a number in [0, 1) (a relative tolerance)."""
    value = _float(text)
    if value is None or not 0.0 <= value < 1.0:
        raise argparse.ArgumentTypeError(f"expected a number >= 0 and < 1, got {text!r}")
    return value


_UNITS = {"": 1, "K": 2**10, "M": 2**20, "G": 2**30, "T": 2**40}


def memory_size(text: str) -> int:
    """An argparse type: bytes as ``512M``, ``2G``, ``1.5GiB``, ``2000000000`` or a share of the
    available memory, ``25%``."""
    t = text.strip().upper().removesuffix("IB").removesuffix("B")
    try:
        if t.endswith("%"):
            share = float(t[:-1])
            if not 0.0 < share <= 100.0:
                raise ValueError
            from ..polytopes.budget import available_memory

            return int(share / 100.0 * available_memory())
        unit = t[-1:] if t[-1:] in _UNITS and t[-1:] != "" else ""
        value = float(t[: len(t) - len(unit)]) * _UNITS[unit]
        if not (math.isfinite(value) and value >= 1.0):
            raise ValueError
        return int(value)
    except (ValueError, IndexError):
        raise argparse.ArgumentTypeError(
            f"expected a size such as 512M, 2G or 25% (of the available memory), got {text!r}"
        ) from None


def numbers(low: float | None = None) -> Callable[[str], tuple[float, ...]]:
    """An argparse type: comma-separated finite numbers ``>= low``."""
    one = number(low)

    def parse(text: str) -> tuple[float, ...]:
        try:
            return tuple(one(v) for v in text.split(","))
        except argparse.ArgumentTypeError:
            bound = "" if low is None else f" >= {low:g}"
            raise argparse.ArgumentTypeError(
                f"expected comma-separated finite numbers{bound}, got {text!r}"
            ) from None

    return parse


def integers(low: int) -> Callable[[str], tuple[int, ...]]:
    """An argparse type: comma-separated integers ``>= low``."""
    one = integer(low)

    def parse(text: str) -> tuple[int, ...]:
        try:
            return tuple(one(v) for v in text.split(","))
        except argparse.ArgumentTypeError:
            raise argparse.ArgumentTypeError(
                f"expected comma-separated integers >= {low}, got {text!r}"
            ) from None

    return parse


def choices(allowed: Sequence[str], *, every: str | None = None) -> Callable[[str], tuple[str, ...]]:
    """An argparse type: distinct comma-separated values of ``allowed`` (``every``: all of them)."""
    expected = ",".join(allowed) + (f" or {every}" if every else "")

    def parse(text: str) -> tuple[str, ...]:
        if every is not None and text.strip() == every:
            return tuple(allowed)
        values = tuple(v.strip() for v in text.split(","))
        if not text.strip() or len(set(values)) != len(values) or any(v not in allowed for v in values):
            raise argparse.ArgumentTypeError(f"expected distinct values among {expected}, got {text!r}")
        return values

    return parse


def names(text: str) -> tuple[str, ...]:
    """An argparse type: non-empty comma-separated names."""
    values = tuple(v.strip() for v in text.split(","))
    if not all(values):
        raise argparse.ArgumentTypeError(f"expected comma-separated names, got {text!r}")
    return values


_STEM = re.compile(r"[A-Za-z0-9_][A-Za-z0-9_.-]*")


def stem(text: str) -> str:
    """An argparse type: a file stem (letters, digits, ``_ . -``; no folder, no leading dot)."""
    if not _STEM.fullmatch(text):
        raise argparse.ArgumentTypeError(
            f"expected a file stem of letters, digits, '_', '.', '-' (no '/'), got {text!r}"
        )
    return text


def folder(text: str) -> str:
    """An argparse type: an output folder (a ``.json``/``.csv`` path is the old file form)."""
    if not text.strip():
        raise argparse.ArgumentTypeError("expected a folder, got ''")
    if Path(text).suffix in (".json", ".csv", ".md") and not Path(text).is_dir():
        raise argparse.ArgumentTypeError(
            f"expected a folder (the output files are written inside it), got the file name {text!r}"
        )
    return text


_CLUSTER = re.compile(r"(?:(tcp|tls|ucx|ws|wss)://)?\[?[A-Za-z0-9_.:-]+\]?:\d{1,5}")


def cluster_address(text: str) -> str:
    """An argparse type: a Dask scheduler address ``[tcp://]HOST:PORT``."""
    if not _CLUSTER.fullmatch(text.strip()) or not 0 < int(text.rsplit(":", 1)[1]) < 65536:
        raise argparse.ArgumentTypeError(f"expected a scheduler address tcp://HOST:PORT, got {text!r}")
    return text.strip()
