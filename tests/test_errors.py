"""A bad argument to a public function is a :class:`~mjtvm.errors.ParamError` naming the
parameter, never a bare ``ValueError`` or a :class:`~mjtvm.errors.StateError` (bad data)."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from mjtvm import tvmmp
from mjtvm.errors import MjtvmError, ParamError, StateError
from mjtvm.formats.state_file import load_state
from mjtvm.model.state import GraspState
from mjtvm.polytopes.budget import Limits
from mjtvm.polytopes.tvms import tvms
from mjtvm.problem2.assembly import assemble
from mjtvm.problem2.dynamic import pair_alpha

EXAMPLE = Path(__file__).resolve().parents[1] / "mjtvm" / "data" / "examples" / "pinch.json"


@pytest.fixture(scope="module")
def pinch() -> GraspState:
    return load_state(EXAMPLE)


def _sweep_point(**kwargs: Any) -> Any:
    from mjtvm.jobs.sweep import SweepPoint

    return SweepPoint(**kwargs)


def _sweep_files(**kwargs: Any) -> Any:
    from mjtvm.jobs.sweep_files import SweepFiles

    return SweepFiles(**kwargs)


def _run_sweep(**kwargs: Any) -> Any:
    from mjtvm.jobs.sweep import run_sweep

    return run_sweep([], progress=False, **kwargs)


def _sim_settings(**kwargs: Any) -> Any:
    from mjtvm.physics.simulate import SimSettings

    return SimSettings(**kwargs)


def _gear_sweep(**kwargs: Any) -> Any:
    from mjtvm.jobs.gears import gear_sweep

    return gear_sweep(**kwargs)


CALLS: list[tuple[str, str, Callable[[GraspState], Any]]] = [
    # (case, the parameter at fault, the call)
    ("tvmmp solver", "solver", lambda s: tvmmp(s, solver="x")),
    ("tvmmp box", "box", lambda s: tvmmp(s, box="x")),  # type: ignore[arg-type]
    ("assemble box", "box", lambda s: assemble(s, box="x")),  # type: ignore[arg-type]
    ("tvms method", "method", lambda s: tvms(s, method="x")),  # type: ignore[arg-type]
    ("tvms scale", "scale", lambda s: tvms(s, scale=[1.0, 2.0])),
    ("limits tolerance", "tolerance", lambda s: Limits(tolerance=1.0)),
    ("sweep point variant", "variant", lambda s: _sweep_point(variant="X")),
    ("sweep point state", "state", lambda s: _sweep_point(state=30)),
    ("sweep jobs", "jobs", lambda s: _run_sweep(jobs=0)),
    ("sweep states", "states", lambda s: _sweep_files(states=(30,), num_states=30)),
    ("simulation cone", "cone", lambda s: _sim_settings(cone="x")),
    ("simulation window", "window", lambda s: _sim_settings(window=-1.0)),
    ("gear ratios", "ratios", lambda s: _gear_sweep(ratios=[0.0])),
]


@pytest.mark.parametrize(("name", "call"), [c[1:] for c in CALLS], ids=[c[0] for c in CALLS])
def test_a_bad_argument_is_a_param_error_naming_it(pinch, name, call):
    with pytest.raises(ParamError) as err:
        call(pinch)
    assert err.value.name == name
    assert str(err.value).startswith(f"{name}: ")
    assert not isinstance(err.value, StateError)


@pytest.mark.parametrize(
    "call", [lambda s: tvmmp(s), lambda s: pair_alpha(s, 0, 0)], ids=["tvmmp", "pair_alpha"]
)
def test_a_state_without_rvds_is_incomplete_data_naming_its_field(pinch, call):
    """Not a bad argument: the state (a file, for the CLI) lacks the field Problem 2 needs."""
    with pytest.raises(StateError, match=r"^rvds: Problem 2 needs RVDS vertices"):
        call(pinch.with_(rvds=None))


def test_a_param_error_is_still_a_value_error_and_an_mjtvm_error():
    """Callers that caught ValueError (or MjtvmError) keep catching it."""
    e = ParamError("box", "expected 'eliminated' or 'literal', got 'x'", "x")
    assert isinstance(e, ValueError) and isinstance(e, MjtvmError)
    assert (e.name, e.value) == ("box", "x")


def test_the_cli_reports_a_param_error_as_bad_input(monkeypatch, capsys):
    """Exit code 2 and one line on stderr, as for every other kind of bad input."""
    import mjtvm.cli.solve
    from mjtvm.cli import main

    def refuse(state: GraspState, **kwargs: Any) -> Any:
        raise ParamError("box", "expected 'eliminated' or 'literal',\ngot 'x'", "x")

    monkeypatch.setattr(mjtvm.cli.solve, "tvmmp", refuse)
    assert main(["solve", str(EXAMPLE)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: box: expected 'eliminated' or 'literal'") and err.count("\n") == 1
