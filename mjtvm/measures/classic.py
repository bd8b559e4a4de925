r"""The classic grasp measures of one grasp state beside its TVMMP (``docs/measures.md``).

[`classic_measures()`][mjtvm.measures.classic.classic_measures] computes, on the same [`GraspState`][mjtvm.model.state.GraspState] that
Problem 2 solves, force closure, the Ferrari-Canny epsilons (L1 and L-infinity), the
smallest singular value of the grasp matrix, Yoshikawa's hand-object manipulability and
the kinematic velocity polytope's volume, each with the torque scale that makes moments
and forces (and angular and linear speeds) commensurable.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Any, Literal

import numpy as np

from mjtvm.errors import ParamError
from mjtvm.measures.kinematics import kinematic_polytope, manipulability
from mjtvm.measures.wrenches import (
    checked_torque_scale,
    closure_margin,
    epsilon_l1,
    epsilon_linf,
    grasp_matrix,
    primitive_wrenches,
    scaled_rank,
)
from mjtvm.model.state import GraspState

__all__ = ["GraspMeasures", "classic_measures"]

TorqueScaleSource = Literal["bounding_radius", "given"]
CLOSURE_TOL = 1e-9  # the closure LP's margin (1 for uniform weights) that counts as > 0


@dataclass(frozen=True)
class GraspMeasures:
    r"""The classic measures of one grasp state (definitions in ``docs/measures.md``).

    Attributes
    ----------
    torque_scale
        ``rho`` (m): moments are divided by it, angular speeds multiplied by it.
    torque_scale_source
        ``"bounding_radius"`` (the largest distance of an F, L or S contact from the object
        position) or ``"given"``.
    friction_edges
        Edges of each spatial friction pyramid (2 in the plane: the exact cone).
    num_wrenches
        Primitive wrenches (force generators of the F, L and S contacts).
    force_closure
        Whether the primitive wrenches positively span the wrench space (the origin strictly
        inside their convex hull): rank ``D`` and a closure margin > 0.
    closure_margin
        ``n max_lam min_k lam_k`` over ``W lam = 0``, ``sum lam = 1`` (dimensionless).
    epsilon_l1
        Ferrari-Canny's L1 epsilon (N per N of total normal force; 0 without closure).
    epsilon_linf
        Ferrari-Canny's L-infinity epsilon (N per N of the largest normal force; 0 without
        closure), a lower bound up to Qhull's round-off.
    epsilon_linf_gap
        Its bracket's width: the true value is at most ``epsilon_linf + epsilon_linf_gap``.
    grasp_sigma_min
        The D-th singular value of the scaled grasp matrix (N per N; 0 below rank D).
    grasp_rank
        The rank of the grasp matrix.
    manipulability
        Yoshikawa's $\sqrt{\det(K_Q K_Q^T)}$ ((m/s)^D per (rad/s)^D); 0 when the
        kinematics do not determine the twist or do not reach every twist.
    twist_determined
        Whether the contact kinematics determine the object twist from the joint speeds.
    velocity_volume
        The kinematic velocity polytope's volume ((m/s)^D in scaled twists; ``inf`` when
        unbounded, 0 below full dimension); ``nan`` when not computed or when its
        projection stopped at the memory budget.
    velocity_dimension
        Its dimension (-1 when empty or not computed).
    velocity_status
        ``"bounded"``, ``"unbounded"`` (the object moves with the hand at rest: volume
        ``inf``), ``"incomplete"`` (the projection stopped at its memory budget: ``nan``) or
        ``"skipped"`` (``polytope=False``): what a ``null`` volume in JSON means.
    """

    torque_scale: float
    torque_scale_source: TorqueScaleSource
    friction_edges: int
    num_wrenches: int
    force_closure: bool
    closure_margin: float
    epsilon_l1: float
    epsilon_linf: float
    epsilon_linf_gap: float
    grasp_sigma_min: float
    grasp_rank: int
    manipulability: float
    twist_determined: bool
    velocity_volume: float
    velocity_dimension: int
    velocity_status: str = "skipped"

    def __post_init__(self) -> None:
        if not (math.isfinite(self.torque_scale) and self.torque_scale > 0.0):
            raise ParamError("torque_scale", f"expected a finite number > 0 (m), got {self.torque_scale!r}")
        if self.torque_scale_source not in ("bounding_radius", "given"):
            raise ParamError(
                "torque_scale_source",
                f"expected 'bounding_radius' or 'given', got {self.torque_scale_source!r}",
            )
        for name in (
            "closure_margin",
            "epsilon_l1",
            "epsilon_linf",
            "epsilon_linf_gap",
            "grasp_sigma_min",
            "manipulability",
        ):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0.0):
                raise ParamError(name, f"expected a finite number >= 0, got {value!r}")
        if self.velocity_status not in ("bounded", "unbounded", "incomplete", "skipped"):
            raise ParamError(
                "velocity_status",
                f"expected 'bounded', 'unbounded', 'incomplete' or 'skipped', got {self.velocity_status!r}",
            )
        if not (math.isnan(self.velocity_volume) or self.velocity_volume >= 0.0):
            raise ParamError(
                "velocity_volume", f"expected a number >= 0, inf or nan, got {self.velocity_volume!r}"
            )

    def to_dict(self) -> dict[str, Any]:
        """The fields as JSON values (``inf`` and ``nan`` as ``None``, ``docs/measures.md``)."""
        out = asdict(self)
        for key, value in out.items():
            if isinstance(value, float) and not math.isfinite(value):
                out[key] = None
        return out


def classic_measures(
    state: GraspState, *, torque_scale: float | None = None, polytope: bool = True
) -> GraspMeasures:
    """Force closure, the Ferrari-Canny epsilons, the grasp matrix's smallest singular value,
    Yoshikawa's manipulability and the kinematic velocity polytope's volume of ``state``.

    Parameters
    ----------
    state
        The grasp state (its contacts, friction pyramids, Jacobians, operation ranges and
        transmission; the REFS, RVDS, gravity torques and preloads play no part).
    torque_scale
        ``rho`` (m, > 0): moments are divided by it and angular speeds multiplied by it;
        default the object's bounding radius from the contacts (the largest distance of an
        F, L or S contact from ``state.object_position``; 1 m when all lie on it).
    polytope
        Compute the velocity polytope (support LPs; the other measures cost a few ms).

    Returns
    -------
    GraspMeasures

    Raises
    ------
    ParamError
        ``torque_scale`` not a finite number > 0.

    References
    ----------
    Ferrari, C. and Canny, J. (1992), Planning optimal grasps, ICRA. Li, Z. and Sastry, S.
    (1988), Task-oriented optimal grasping by multifingered robot hands, IEEE J. Robot.
    Autom. 4(1). Li, Z., Hsu, P. and Sastry, S. (1989), Grasping and coordinated
    manipulation by a multifingered robot hand, IJRR 8(4). Yoshikawa, T. (1985),
    Manipulability of robotic mechanisms, IJRR 4(2). Miller, A. and Allen, P. (2004),
    GraspIt!, IEEE Robot. Autom. Mag. 11(4).
    """
    rho = checked_torque_scale(state, torque_scale)
    groups = primitive_wrenches(state, rho)
    big_d = state.twist_dim
    allw = np.hstack([np.zeros((big_d, 0)), *groups])  # no contact: no wrench
    margin = closure_margin(allw)
    closure = scaled_rank(allw) == big_d and margin > CLOSURE_TOL
    eps_inf, gap = epsilon_linf(groups, margin=margin) if closure else (0.0, 0.0)
    g = grasp_matrix(state, rho)
    sv = np.linalg.svd(g, compute_uv=False) if g.size else np.zeros(0)
    sigma_min = float(sv[big_d - 1]) if sv.size >= big_d else 0.0
    w, determined = manipulability(state, rho)
    volume, dim, status = (float("nan"), -1, "skipped")
    if polytope:
        volume, dim, _ = kinematic_polytope(state, rho)
        status = "unbounded" if math.isinf(volume) else "incomplete" if math.isnan(volume) else "bounded"
    return GraspMeasures(
        torque_scale=rho,
        torque_scale_source="bounding_radius" if torque_scale is None else "given",
        friction_edges=state.friction_edges if state.dim == 3 else 2,
        num_wrenches=int(allw.shape[1]),
        force_closure=bool(closure),
        closure_margin=max(0.0, margin),
        epsilon_l1=epsilon_l1(allw, margin=margin) if closure else 0.0,
        epsilon_linf=eps_inf,
        epsilon_linf_gap=gap,
        grasp_sigma_min=sigma_min,
        grasp_rank=scaled_rank(g),
        manipulability=w,
        twist_determined=determined,
        velocity_volume=volume,
        velocity_dimension=dim,
        velocity_status=status,
    )
