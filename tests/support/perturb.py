r"""Perturbed grasp states for the differential tests: unit changes, S-points, near-singular
Jacobians and round-off noise.

Every function returns a new :class:`~mjtvm.model.state.GraspState`; none needs MuJoCo. Which
ones keep the alphas of Problem 2 (eq. 31-35) exactly, and why:

* :func:`rescale` (length, force, time units) and :func:`rescale_joints` (the joints' unit)
  are changes of unit: every row of the LP is multiplied by one factor and every variable by
  one factor, and ``alpha`` (dimensionless, eq. 31) is unchanged;
* :func:`add_jacobian_roundoff` writes noise below the round-off rule of
  :mod:`~mjtvm.lp.roundoff` into the exact zeros of the Jacobians: the state is the same
  state written inexactly, and its alphas are those of the clean one;
* :func:`scale_joint_column` (a joint that barely moves its contacts, a finger near its
  stretched pose) and :func:`slide_contact` (an S-point) change the problem.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from numpy.typing import NDArray

from mjtvm.lp.roundoff import DROP_REL
from mjtvm.model.contacts import tangent_basis
from mjtvm.model.limits import JointLimits
from mjtvm.model.operation_range import OperationRange
from mjtvm.model.state import GraspState

__all__ = [
    "RANDOM_TYPES",
    "add_jacobian_roundoff",
    "random_case",
    "rescale",
    "rescale_joints",
    "scale_joint_column",
    "scale_range",
    "slide_contact",
]


def scale_range(op: OperationRange, torque: float, speed: float) -> OperationRange:
    """``op`` with its torque axis times ``torque`` and its speed axis times ``speed``.

    Built from the exactly transformed half-planes (``a^T x <= b`` becomes
    ``(a / D)^T x' <= b``, renormalised), not through ``OperationRange(vertices)``: that
    recomputes the half-planes from the scaled vertices and sets coefficients below 1e-15
    to 0 (an absolute bound), which changes a range whose axes differ by ~1e18 (torque axis
    times 1e-12, speed axis times 1e6). The solver's invariance is what the callers test.

    Parameters
    ----------
    op
        The operation range.
    torque, speed
        Positive factors of the torque and speed axes.

    Returns
    -------
    OperationRange
        The scaled range (same vertex order).
    """
    v = op.vertices * np.array([torque, speed])
    hp = op.halfplanes.copy()
    hp[:, 0] /= torque
    hp[:, 1] /= speed
    hp /= np.linalg.norm(hp[:, :2], axis=1, keepdims=True)
    hp.setflags(write=False)
    v.setflags(write=False)
    out = object.__new__(OperationRange)
    object.__setattr__(out, "vertices", v)
    object.__setattr__(out, "_halfplanes", hp)
    return out


def rescale(state: GraspState, *, length: float = 1.0, force: float = 1.0, time: float = 1.0) -> GraspState:
    """``state`` in units whose length, force and time units are SI divided by the factors.

    A quantity of dimension L^a F^b T^c is multiplied by ``length^a force^b time^c``:
    positions and Jacobians (revolute joints) by ``length``, torques (operation ranges,
    gravity torques, REFS moments) by ``force * length``, REFS forces by ``force``, speeds
    (operation ranges, RVDS angular rows) by ``1 / time``, RVDS linear rows by
    ``length / time``. Unit vectors (normals, tangents, slide directions) are unchanged.

    Parameters
    ----------
    state
        A grasp state in any units.
    length, force, time
        Positive factors.

    Returns
    -------
    GraspState
        The same grasp in the new units: Problem 2 has the same alphas.
    """
    d = state.dim
    contacts = tuple(
        replace(c, position=c.position * length, jacobian=c.jacobian * length) for c in state.contacts
    )
    ranges = tuple(scale_range(op, force * length, 1.0 / time) for op in state.operation_ranges)
    wscale = np.concatenate([np.full(d, force), np.full(state.twist_dim - d, force * length)])
    rscale = np.concatenate([np.full(d, length / time), np.full(state.twist_dim - d, 1.0 / time)])
    return replace(
        state,
        object_position=state.object_position * length,
        contacts=contacts,
        operation_ranges=ranges,
        gravity_torque=state.gravity_torque * force * length,
        refs=state.refs * wscale,
        rvds=None if state.rvds is None else state.rvds * rscale,
        # the joint limits' horizon is a length (m of object travel); the angles are not
        joint_limits=None
        if state.joint_limits is None
        else state.joint_limits.with_options(horizon=state.joint_limits.horizon * length),
    )


def rescale_joints(state: GraspState, factor: float) -> GraspState:
    r"""``state`` with every joint angle measured in a unit ``1 / factor`` rad.

    A joint speed :math:`\dot q' = \dot q / s` gives the same contact velocity with
    :math:`J' = s J`; the power :math:`\tau \dot q` is unchanged, so :math:`\tau' = s \tau`:
    Jacobians, gravity torques and the operation ranges' torque axes are multiplied by
    ``factor``, the ranges' speed axes divided by it. With ``factor = 1e-6`` every Jacobian
    entry is ~1e-7 (tiny coefficients that must not be taken for round-off) and the alphas
    are those of ``state``.

    Parameters
    ----------
    state
        A grasp state.
    factor
        Positive factor ``s``.

    Returns
    -------
    GraspState
        The same grasp in the new joint unit.
    """
    contacts = tuple(replace(c, jacobian=c.jacobian * factor) for c in state.contacts)
    ranges = tuple(scale_range(op, factor, 1.0 / factor) for op in state.operation_ranges)
    lim = state.joint_limits
    if lim is not None:  # angles q' = q / s: positions, ranges and the tolerance
        lim = JointLimits(
            lim.position / factor, lim.lower / factor, lim.upper / factor, lim.tolerance / factor, lim.horizon
        )
    return replace(
        state,
        contacts=contacts,
        operation_ranges=ranges,
        gravity_torque=state.gravity_torque * factor,
        joint_limits=lim,
    )


def scale_joint_column(state: GraspState, joint: int, factor: float) -> GraspState:
    """``state`` with column ``joint`` of every contact Jacobian multiplied by ``factor``.

    With a small factor the joint barely moves its contacts: a finger close to a singular
    (stretched) pose, whose joint speed for a given contact velocity is ``1 / factor``
    times larger and whose torque for a given force ``factor`` times smaller. A different
    grasp: its alphas are not ``state``'s.

    Parameters
    ----------
    state
        A grasp state.
    joint
        Column index, ``0 <= joint < M``.
    factor
        The multiplier.

    Returns
    -------
    GraspState
        The perturbed state.
    """
    if not 0 <= joint < state.num_joints:
        raise ValueError(f"joint: expected an index in [0, {state.num_joints}), got {joint}")
    contacts = []
    for c in state.contacts:
        jac = c.jacobian.copy()
        jac[:, joint] *= factor
        contacts.append(replace(c, jacobian=jac))
    return replace(state, contacts=tuple(contacts))


def slide_contact(state: GraspState, index: int, angle: float) -> GraspState:
    r"""``state`` with contact ``index`` made an S-point sliding along
    :math:`\cos\theta\, t_1 + \sin\theta\, t_2` (:func:`~mjtvm.model.contacts.tangent_basis`
    of its normal and tangent; in the plane :math:`\pm t_1` by the sign of :math:`\cos\theta`).

    Parameters
    ----------
    state
        A grasp state whose contact ``index`` has a friction coefficient (F or S).
    index
        The contact.
    angle
        :math:`\theta` (rad).

    Returns
    -------
    GraspState
        The state with that contact of type ``"S"``.
    """
    c = state.contacts[index]
    if c.mu is None:
        raise ValueError(f"contact {c.name!r} has no friction coefficient: it cannot be an S-point")
    t = tangent_basis(c.normal, c.tangent)
    if c.dim == 2:
        slide = (1.0 if np.cos(angle) >= 0.0 else -1.0) * t[0]
    else:
        slide = np.cos(angle) * t[0] + np.sin(angle) * t[1]
    contacts = list(state.contacts)
    contacts[index] = replace(c, type="S", slide_direction=slide)
    return replace(state, contacts=tuple(contacts))


def add_jacobian_roundoff(
    state: GraspState, rng: np.random.Generator, *, low: float = 1e-18, high: float = 1e-14
) -> GraspState:
    """``state`` with noise of magnitude in ``[low, high]`` (log-uniform, random sign) in every
    exact zero of every contact Jacobian (also the all-zero Jacobians of D-points).

    The noise must be round-off by :mod:`~mjtvm.lp.roundoff`'s rule: ``high`` at most
    ``DROP_REL`` times the state's largest Jacobian entry (else it would be data, and the
    alphas would not be the clean state's).

    Parameters
    ----------
    state
        A grasp state with a non-zero Jacobian entry.
    rng
        The random generator (seeded by the caller).
    low, high
        Bounds of the noise's magnitude, ``0 < low <= high``.

    Returns
    -------
    GraspState
        The noisy state (its non-zero entries unchanged).

    Raises
    ------
    ValueError
        When ``high`` exceeds the round-off threshold of the state.
    """
    biggest = max((float(np.max(np.abs(c.jacobian))) for c in state.contacts), default=0.0)
    if not 0.0 < low <= high <= DROP_REL * biggest:
        raise ValueError(
            f"noise up to {high:g} is not round-off for Jacobian entries up to {biggest:g} "
            f"(at most {DROP_REL:g} of them)"
        )
    contacts = []
    for c in state.contacts:
        jac = c.jacobian.copy()
        zero = jac == 0.0
        jac[zero] = _noise(rng, int(zero.sum()), low, high)
        contacts.append(replace(c, jacobian=jac))
    return replace(state, contacts=tuple(contacts))


def _noise(rng: np.random.Generator, n: int, low: float, high: float) -> NDArray[np.float64]:
    """``n`` values of log-uniform magnitude in ``[low, high]`` and random sign."""
    mag = np.exp(rng.uniform(np.log(low), np.log(high), size=n))
    return np.where(rng.uniform(size=n) < 0.5, -mag, mag)


#: Contact types of the random families (contact i on finger i % 4; D on the fixed base).
RANDOM_TYPES: tuple[tuple[str, ...], ...] = (
    ("F", "L", "F", "L", "D"),
    ("F", "S", "F", "S", "D"),
    ("F", "L", "S", "L", "D"),
    ("L", "S", "F", "S"),
    ("F", "F", "F"),
)


def random_case(seed: int) -> tuple[str, GraspState]:
    """A seeded random state of :func:`~benchmarks.synthetic.random_state` and its family name
    (``random-<space>d-<types>``): the seed picks the space (2 or 3), the contact types among
    :data:`RANDOM_TYPES`, one or two REFS vertices, 4 or 6 RVDS vertices and the slip mode.

    Parameters
    ----------
    seed
        Any non-negative integer; the same seed gives the same state.

    Returns
    -------
    tuple
        ``(family, state)``.
    """
    from benchmarks.synthetic import random_state

    rng = np.random.default_rng([seed, 0x5EED])
    space = int(rng.choice([2, 3]))
    types = RANDOM_TYPES[int(rng.integers(len(RANDOM_TYPES)))]
    state = random_state(
        rng,
        space=space,
        contact_types=types,
        num_refs=int(rng.integers(1, 3)),
        num_rvds=int(rng.choice([4, 6])),
        mu=float(rng.uniform(0.2, 0.8)),
    )
    if "S" in types and rng.uniform() < 0.25:
        state = state.with_(slip="shared")
    return f"random-{space}d-{''.join(types)}", state


def random_transmission(state: GraspState, rng: np.random.Generator, *, hold: bool = True) -> GraspState:
    """``state`` driven through a random transmission: M - 1 actuators (the last joint's
    torque shared: a tendon over two joints), one coupling row between the first two joints,
    small joint damping; each actuator's range the first ranges of ``state``. With ``hold`` a
    second coupling row ties the tendon's two joints, so that no joint motion is left free;
    without it the tendon's split is free (the Shadow hand's sum tendon), which the REFS
    usually need held (mjtvm.problem2.holding)."""
    from mjtvm.model.transmission import Transmission

    m = state.num_joints
    a = max(1, m - 1)
    moment = np.eye(a, m)
    moment[a - 1, m - 1] = float(rng.uniform(0.3, 1.5))  # the last actuator pulls two joints
    moment[: a - 1] *= rng.uniform(0.5, 2.0, size=(a - 1, 1))
    coupled: list[tuple[str, tuple[int, int]]] = [("coupling", (0, 1))] if m >= 3 else []
    if hold and m >= 4:
        coupled.append(("tendon-coupling", (m - 2, m - 1)))
    rows, names = None, ()
    if coupled:
        rows, names = np.zeros((len(coupled), m)), tuple(n for n, _ in coupled)
        for row, (_, (i, j)) in zip(rows, coupled, strict=True):
            row[[i, j]] = [1.0, -float(rng.uniform(0.5, 1.5))]
    t = Transmission(
        tuple(f"act{i}" for i in range(a)),
        moment,
        names,
        rows,
        rng.uniform(0.0, 0.01, size=m),
    )
    return state.with_(operation_ranges=state.operation_ranges[:a], transmission=t)
