"""The paper's objects: grasp states, contacts, operation ranges, transmissions, joint limits.

A [`GraspState`][mjtvm.model.state.GraspState] holds one grasp: its
[`Contact`][mjtvm.model.contacts.Contact] points with their friction pyramids, one
[`OperationRange`][mjtvm.model.operation_range.OperationRange] per actuator, an optional
[`Transmission`][mjtvm.model.transmission.Transmission] from actuators to joints, and optional
[`JointLimits`][mjtvm.model.limits.JointLimits]; ``bounds`` checks every number a state is
built from, ``friction`` the friction margin.

This room imports only ``mjtvm.lp`` and ``mjtvm.errors`` (import-linter's layers in
``pyproject.toml``).
"""

from mjtvm.model.contacts import CONTACT_TYPES, Contact, force_generators, tangent_basis
from mjtvm.model.limits import JointLimits, travel_speed, with_limit_horizon
from mjtvm.model.operation_range import OperationRange, default_operation_range, load_motor_data
from mjtvm.model.state import GraspState
from mjtvm.model.transmission import Transmission

__all__ = [
    "CONTACT_TYPES",
    "Contact",
    "GraspState",
    "JointLimits",
    "OperationRange",
    "Transmission",
    "default_operation_range",
    "force_generators",
    "load_motor_data",
    "tangent_basis",
    "travel_speed",
    "with_limit_horizon",
]
