r"""The one exception family of mjtvm.

Every error the package raises on purpose derives from [`MjtvmError`][mjtvm.errors.MjtvmError], and
carries the offending data as attributes so that callers (and tests) need not
parse messages.
"""

from __future__ import annotations

from typing import Any

__all__ = [
    "MjtvmError",
    "ModelError",
    "OptionError",
    "OutputError",
    "ParamError",
    "SolverError",
    "StateError",
]


class MjtvmError(Exception):
    """Base class of every error raised by mjtvm."""


class StateError(MjtvmError, ValueError):
    r"""Invalid input data: a grasp state, an operation range, a JSON file.

    Parameters
    ----------
    field
        Path of the offending field, e.g. ``"contacts[2].normal"``.
    problem
        What was expected and what was found.
    value
        The offending value, when there is one.
    """

    def __init__(self, field: str, problem: str, value: Any = None) -> None:
        self.field = field
        self.problem = problem
        self.value = value
        super().__init__(f"{field}: {problem}" if field else problem)

    def under(self, prefix: str) -> StateError:
        """Return the same error with ``prefix`` prepended to its field path."""
        field = f"{prefix}.{self.field}" if self.field else prefix
        if self.field.startswith("["):
            field = f"{prefix}{self.field}"
        return type(self)(field, self.problem, self.value)


class ParamError(MjtvmError, ValueError):
    r"""A bad argument to a Python function of the package: not bad data (a state, a grasp
    file, a model: [`StateError`][mjtvm.errors.StateError], [`ModelError`][mjtvm.errors.ModelError]) and not a command-line option
    ([`OptionError`][mjtvm.errors.OptionError]).

    Parameters
    ----------
    name
        The parameter at fault, e.g. ``"box"``.
    problem
        What was expected and what was found.
    value
        The offending value, when there is one.
    """

    def __init__(self, name: str, problem: str, value: Any = None) -> None:
        self.name = name
        self.problem = problem
        self.value = value
        super().__init__(f"{name}: {problem}")


class OptionError(MjtvmError, ValueError):
    r"""Command-line options that are each well formed but do not fit together or exceed what
    a run may take (e.g. a sweep grid of too many points).

    Parameters
    ----------
    option
        The option at fault as typed, e.g. ``"--mu"``.
    problem
        What was expected and what was found.
    """

    def __init__(self, option: str, problem: str) -> None:
        self.option = option
        self.problem = problem
        super().__init__(f"{option}: {problem}")


class SolverError(MjtvmError, RuntimeError):
    r"""A linear-program solver failed or returned a status mjtvm cannot interpret.

    Parameters
    ----------
    solver
        Name of the backend (``"highs"``, ``"clarabel"``, ...).
    status
        The solver's own status string.
    pair
        The (REFS index k, RVDS index l) of the failing LP, when known.
    """

    def __init__(self, solver: str, status: str, pair: tuple[int, int] | None = None) -> None:
        self.solver = solver
        self.status = status
        self.pair = pair
        where = f" for (k, l) = {pair}" if pair is not None else ""
        super().__init__(f"solver {solver!r} returned status {status!r}{where}")


class ModelError(MjtvmError, ValueError):
    r"""An MJCF model or scenario that does not fit what mjtvm needs.

    Parameters
    ----------
    what
        The missing or malformed item, e.g. ``"joint 'f3_yaw2'"``.
    problem
        What is wrong with it.
    """

    def __init__(self, what: str, problem: str) -> None:
        self.what = what
        self.problem = problem
        super().__init__(f"{what}: {problem}")


class OutputError(MjtvmError):
    r"""An output file or folder that cannot be written (or is in use by another run).

    Parameters
    ----------
    option
        The command-line option (or argument name) that named the path, e.g. ``"--out"``.
    path
        The offending path.
    problem
        What went wrong, e.g. ``"not a directory"``.
    """

    def __init__(self, option: str, path: str, problem: str) -> None:
        self.option = option
        self.path = path
        self.problem = problem
        super().__init__(f"{option}: {problem}: {path}" if option else f"{problem}: {path}")
