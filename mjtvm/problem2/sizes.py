r"""The physical sizes of Problem 2's variables and rows, which its certificates measure against.

[`StateLPs`][mjtvm.problem2.lps.StateLPs] certifies every answer on the unscaled LP
([`certificate`][mjtvm.lp.certificate]); a row's violation, and a reduced cost of the wrong sign,
is measured against sizes taken from the state (its operation ranges, its Jacobians' scale,
its REFS), never from the equilibration, which the certificate must not trust.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from mjtvm.lp.roundoff import jacobian_scale
from mjtvm.model.state import GraspState
from mjtvm.model.transmission import joint_speed_limits
from mjtvm.problem2.assembly import Assembly

__all__ = ["physical_sizes"]


def physical_sizes(state: GraspState, asm: Assembly) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """``(n + 1,)`` the sizes the certificate measures a row's violation, and a reduced cost
    of the wrong sign, at where the solution is ~0 ([`certify()`][mjtvm.lp.certificate.certify]'s
    ``col_ref``): each joint's largest speed and torque (its operation range) for the
    speeds, torques, damping losses and the literal box's variables; for the force generators' weights the
    larger of the weight and the largest torque over the Jacobians' scale; for the
    slip speeds the largest joint speed times that scale; alpha its own value. From the
    state, never from the equilibration, which the certificate must not trust.

    And ``(m,)`` the largest a term at those sizes may add to a row's scale (the
    [`Certifier`][mjtvm.lp.certifier.Certifier]'s ``row_cap``): on the kinematic rows (a
    contact's relative velocity, eq. 11-13) the speed the hand's joints move a contact at,
    ``sqrt(d)`` times the Jacobians' scale ([`jacobian_scale()`][mjtvm.lp.roundoff.jacobian_scale])
    times the fastest joint; ``inf`` on every other row. A row of unit vectors times the
    Jacobians has entries at most ``sqrt(d)`` times their largest, so no term reaches the
    cap unless one entry stands alone far above the others (1e12 among lever arms of
    0.1 m): that joint at its top speed is not a speed the row has in any solution whose
    contacts move with the object, and as the row's scale it would pass a contact velocity
    missed by 100 % for round-off (the solution's own term ``|A_ij qd_j|`` counts in full)."""
    size = np.zeros(asm.num_variables + 1)
    speed = np.array([op.max_speed for op in state.operation_ranges])
    torque = np.array([op.max_torque for op in state.operation_ranges])
    joint_speed, joint_torque = speed, torque
    if state.transmission is not None:
        # Through the moment P: a joint's speed is at most the fastest |s_a / P_aj| of the
        # actuators moving it, its torque at most sum_a |P_aj| u_a; a passive joint's speed
        # (no actuator) is measured at the fastest of them all.
        joint_speed = joint_speed_limits(state.transmission.moment, speed)
        joint_torque = np.abs(state.transmission.moment).T @ torque
    # A contact force is at most what the weight and the strongest joint through the largest
    # Jacobian entry give; a slip speed at most the fastest joint through it (the largest
    # entry unless it stands alone, roundoff.jacobian_scale: then the hand's lever arms).
    jac = jacobian_scale([c.jacobian for c in state.contacts])
    weight = float(np.max(np.linalg.norm(state.refs[:, : state.dim], axis=1), initial=0.0))
    force = max(weight, float(joint_torque.max(initial=0.0)) / jac if jac > 0.0 else 0.0)
    slip = float(joint_speed.max(initial=0.0)) * jac
    for name, sl in asm.blocks.items():
        if name.startswith("tau") or name == "loss":
            size[sl] = torque
        elif name.startswith("qd"):
            size[sl] = speed if name != "qd" else joint_speed
        elif name.startswith("lam"):
            size[sl] = force
        elif name == "rho":
            size[sl] = slip
        elif name.startswith("eq"):  # a constraint force: a torque through its row's largest entry
            assert state.transmission is not None and state.transmission.constraint_jacobian is not None
            jeq = state.transmission.constraint_jacobian
            size[sl] = float(joint_torque.max(initial=0.0)) / np.max(np.abs(jeq), axis=1)
    cap = np.full(asm.csc.shape[0], np.inf)
    cap[asm.kinematic_rows] = np.sqrt(state.dim) * slip
    return size, cap
