"""Lazy re-exports: a package's public names imported from their modules on first use."""

from __future__ import annotations

import importlib
from collections.abc import Callable, Mapping
from typing import Any

__all__ = ["lazy_attributes"]


def lazy_attributes(package: str, homes: Mapping[str, str]) -> Callable[[str], Any]:
    """The module-level ``__getattr__`` of ``package`` (PEP 562).

    Parameters
    ----------
    package
        The package's ``__name__``.
    homes
        Public name -> the module, relative to ``package``, that defines it.

    Returns
    -------
    callable
        ``__getattr__(name)``: ``name`` imported from ``homes[name]`` on first use, so that
        importing the package loads neither MuJoCo nor rerun before a name that needs them
        is used; ``AttributeError`` for any other name.
    """

    def __getattr__(name: str) -> Any:
        if name in homes:
            return getattr(importlib.import_module(f".{homes[name]}", package), name)
        raise AttributeError(f"module {package!r} has no attribute {name!r}")

    return __getattr__
