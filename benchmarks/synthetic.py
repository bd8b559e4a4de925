r"""Seeded synthetic grasp states that are feasible by construction.

Used by the property tests, the solver cross-checks and the benchmarks when a
simulator-free state of a given size is wanted. A sphere of radius ``radius`` centred
at ``object_position`` is touched at random points; each finger's contacts get a
random Jacobian in that finger's columns only; the REFS vertices are the wrenches that
randomly drawn admissible contact forces balance, scaled so that the joint torques use
at most ``load`` of the smallest torque limit. So every REFS vertex is balanceable
within the operation ranges and friction, and every LP of Problem 2 is feasible.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from mjtvm.errors import ParamError
from mjtvm.model.contacts import Contact, force_generators
from mjtvm.model.operation_range import OperationRange, default_operation_range
from mjtvm.model.state import GraspState
from mjtvm.problem2.assembly import grasp_map_transpose

__all__ = ["PAPER_RVDS", "random_state"]

#: The paper's RVDS of Case 2 (eq. 37, typo fixed): four upward diagonal directions.
PAPER_RVDS = np.array(
    [[1, 1, 1, 0, 0, 0], [1, -1, 1, 0, 0, 0], [-1, 1, 1, 0, 0, 0], [-1, -1, 1, 0, 0, 0]], float
)


def _random_contacts(
    rng: np.random.Generator,
    p_o: NDArray[np.float64],
    radius: float,
    m: int,
    offsets: Sequence[int],
    contact_types: Sequence[str],
    mu: float,
) -> list[Contact]:
    """Contacts at random points of the sphere, normals into the object; contact i on
    finger ``i % fingers`` with a random Jacobian in that finger's columns only (finger f's
    joints are columns ``offsets[f]:offsets[f + 1]``), D contacts on the fixed base (below,
    zero Jacobian), S contacts with a random slide."""
    fingers = len(offsets) - 1
    d = len(p_o)
    contacts = []
    for i, ctype in enumerate(contact_types):
        direction = rng.normal(size=d)
        if ctype == "D":
            direction = -np.eye(d)[-1] + 0.2 * rng.normal(size=d)
        direction /= np.linalg.norm(direction)
        position = p_o + radius * direction
        jac = np.zeros((d, m))
        if ctype != "D":
            finger = i % fingers
            cols = slice(offsets[finger], offsets[finger + 1])
            jac[:, cols] = 0.1 * rng.normal(size=(d, cols.stop - cols.start))
        slide = None
        if ctype == "S":
            slide = rng.normal(size=d)
        contacts.append(
            Contact(f"c{i}", ctype, position, -direction, jac, mu=mu, slide_direction=slide)  # type: ignore[arg-type]
        )
    return contacts


def _balanced_refs(
    rng: np.random.Generator,
    contacts: list[Contact],
    p_o: NDArray[np.float64],
    budget: NDArray[np.float64],
    num_refs: int,
    friction_edges: int,
) -> NDArray[np.float64]:
    """REFS vertices ``-w`` that random admissible contact forces ``f = E lam`` balance
    (eq. 19-20), scaled so that the joint torques ``J^T f`` stay within ``budget``."""
    big_d = 3 if len(p_o) == 2 else 6
    m = len(budget)
    refs = []
    for _ in range(num_refs):
        wrench = np.zeros(big_d)
        torque = np.zeros(m)
        for c in contacts:
            gen = force_generators(c, friction_edges)
            f = gen @ rng.uniform(0, 1, size=gen.shape[1])
            wrench += grasp_map_transpose(c.position, p_o).T @ f
            torque += c.jacobian.T @ f
        scale = 1.0
        if np.max(np.abs(torque)) > 0:
            scale = float(np.min(budget) / np.max(np.abs(torque)))
        refs.append(-scale * wrench)
    return np.array(refs)


def random_state(
    seed: int | np.random.Generator,
    *,
    space: int = 3,
    fingers: int = 4,
    joints_per_finger: int | Sequence[int] = 4,
    contact_types: Sequence[str] = ("F", "L", "F", "L", "D"),
    num_refs: int = 1,
    num_rvds: int = 4,
    mu: float = 0.5,
    load: float = 0.5,
    gravity_scale: float = 0.05,
    operation_range: OperationRange | None = None,
    friction_edges: int = 16,
    radius: float = 0.1,
    rvds: NDArray[np.float64] | None = None,
) -> GraspState:
    r"""A random grasp state, feasible by construction (see the module docstring).

    Parameters
    ----------
    seed
        Seed or generator (results are reproducible).
    space
        2 or 3.
    fingers, joints_per_finger
        Hand size: M = fingers x joints_per_finger, or ``sum(joints_per_finger)`` when it is
        one count per finger (``len(joints_per_finger) == fingers``).
    contact_types
        One type per contact; contact i lies on finger ``i % fingers``, except D
        contacts, which are on the fixed base (zero Jacobian).
    num_refs, num_rvds
        Number of REFS and RVDS vertices. The RVDS is the paper's (eq. 37) when
        ``space == 3`` and ``num_rvds == 4``, random directions otherwise.
    rvds
        ``(L, D)`` RVDS vertices given explicitly (``num_rvds`` is then ignored); drawn after
        the contacts and REFS, so the rest of the state is the same as without it.
    mu
        Friction coefficient of every contact.
    load
        Fraction of the smallest torque limit the REFS torques may use.
    gravity_scale
        Scale of the random gravity torques g_f (N m).
    """
    rng = seed if isinstance(seed, np.random.Generator) else np.random.default_rng(seed)
    d = space
    big_d = 3 if d == 2 else 6
    per_finger = (
        [joints_per_finger] * fingers if isinstance(joints_per_finger, int) else list(joints_per_finger)
    )
    if len(per_finger) != fingers:
        raise ParamError("joints_per_finger", f"expected {fingers} counts, got {len(per_finger)}", per_finger)
    offsets = np.concatenate([[0], np.cumsum(per_finger)]).astype(int).tolist()
    m = offsets[-1]
    finger_of = np.repeat(np.arange(fingers), per_finger)
    index_in = np.arange(m) - np.asarray(offsets[:-1])[finger_of]
    op = operation_range or default_operation_range()
    p_o = np.zeros(d)
    p_o[-1] = radius
    contacts = _random_contacts(rng, p_o, radius, m, offsets, contact_types, mu)
    g_f = gravity_scale * rng.uniform(-1, 1, size=m)
    budget = load * op.max_torque - np.abs(g_f)
    refs = _balanced_refs(rng, contacts, p_o, budget, num_refs, friction_edges)
    if rvds is not None:
        rvds = np.array(rvds, dtype=float)
    elif d == 3 and num_rvds == 4:
        rvds = PAPER_RVDS.copy()
    else:
        rvds = rng.normal(size=(num_rvds, big_d))
    return GraspState(
        space=d,
        object_position=p_o,
        joint_names=tuple(f"f{finger_of[j] + 1}_j{index_in[j]}" for j in range(m)),
        operation_ranges=(op,) * m,
        gravity_torque=g_f,
        contacts=tuple(contacts),
        refs=refs,
        rvds=rvds,
        friction_edges=friction_edges,
    )
