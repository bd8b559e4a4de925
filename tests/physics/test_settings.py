"""The rollouts' settings (mjtvm.physics.settings): the integrator choice and `with_integration`."""

from __future__ import annotations

import mujoco
import pytest

from mjtvm.errors import ParamError
from mjtvm.physics.disturb import HOLD_SETTINGS
from mjtvm.physics.settings import SimSettings, sim_model, with_integration

_XML = """
<mujoco>
  <option timestep="0.002" integrator="{integrator}"/>
  <worldbody>
    <geom name="floor" type="plane" size="1 1 0.1"/>
    <body name="object"><freejoint/><geom type="box" size="0.02 0.02 0.02" mass="0.1"/></body>
  </worldbody>
</mujoco>"""


def _model(integrator: str) -> mujoco.MjModel:
    return mujoco.MjModel.from_xml_string(_XML.format(integrator=integrator))


def test_none_keeps_the_models_integrator_and_a_name_sets_it() -> None:
    for name, value in (
        ("Euler", mujoco.mjtIntegrator.mjINT_EULER),
        ("implicitfast", mujoco.mjtIntegrator.mjINT_IMPLICITFAST),
    ):
        m = sim_model(_model(name), {}, mu=0.5)  # SimSettings(): integrator None
        assert m.opt.integrator == value and m.opt.timestep == 2.5e-4
    m = sim_model(_model("Euler"), {}, mu=0.5, settings=SimSettings(integrator="implicitfast"))
    assert m.opt.integrator == mujoco.mjtIntegrator.mjINT_IMPLICITFAST


def test_with_integration_copies_only_when_it_changes_something() -> None:
    m = sim_model(_model("Euler"), {}, mu=0.5)
    assert with_integration(m, SimSettings()) is m  # the model's step, its own integrator
    hold = with_integration(m, HOLD_SETTINGS)
    assert hold is not m and (hold.opt.timestep, hold.opt.integrator) == (
        1e-3, mujoco.mjtIntegrator.mjINT_IMPLICITFAST,
    )  # fmt: skip
    assert (m.opt.timestep, m.opt.integrator) == (2.5e-4, mujoco.mjtIntegrator.mjINT_EULER)  # untouched
    assert with_integration(hold, HOLD_SETTINGS) is hold


def test_an_unknown_integrator_is_refused_naming_the_field() -> None:
    with pytest.raises(ParamError, match="integrator") as e:
        SimSettings(integrator="verlet")  # type: ignore[arg-type]
    assert "verlet" in str(e.value)
