r"""mjtvm against the library a user would pick instead, on its home ground: pycapacity 2.1.9.

With no wrench to balance (REFS = {0}) and one fingertip contact, the TVMS restricted to
the translations (RVDS $\pm e_x, \pm e_y, \pm e_z$) is the classic velocity polytope
$\{J \dot q : |\dot q| \le \dot q_{max}\}$ of the fingertip's Jacobian
([`speed_box`][mjtvm.polytopes.speed_box]). Measured in one run, per finger of 3, 4, 7 and 12
joints ([`fingertip_state()`][benchmarks.peers.fingertip_state]: a random spatial chain, the paper's motor at every joint):

* ``tvms``: [`tvms()`][mjtvm.polytopes.tvms.tvms] on the state (``method="auto"``: the
  zonotope; its volume and alphas included), against pycapacity's ``velocity_polytope``
  (hyperplane shifting, a Chebyshev centre by GLPK, Qhull's halfspace intersection): the
  pair interleaved ``repeats`` times, medians, ``ratio`` = pycapacity / mjtvm (above 1:
  mjtvm faster);
* ``function``: [`velocity_polytope()`][mjtvm.polytopes.capacity.velocity_polytope] on the same Jacobian, the
  same way, and [`force_polytope()`][mjtvm.polytopes.capacity.force_polytope] against pycapacity's
  ``force_polytope`` (vertex enumeration ``vepoli2``) on the torque box;
* ``lp``: the LP projection on the same state (``method="lp"``, as before this path
  existed), a few repeats;
* agreement: the Hausdorff distance of the vertex sets (mjtvm's zonotope against the LP
  path and against pycapacity), relative to the extent, and the vertex counts;
* pycapacity's own example, its four-link planar robot (``pycapacity.examples``), velocity
  and force polytopes.

pycapacity is optional: without it the peer columns are ``None``.
"""

from __future__ import annotations

import importlib.metadata
import statistics
import time
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mjtvm.model.contacts import Contact
from mjtvm.model.operation_range import default_operation_range
from mjtvm.model.state import GraspState
from mjtvm.polytopes.capacity import force_polytope, velocity_polytope
from mjtvm.polytopes.hull import distinct
from mjtvm.polytopes.tvms import tvms
from mjtvm.polytopes.volume import hausdorff

__all__ = ["PEER_JOINTS", "TARGET_RATIO", "bench_peers", "fingertip_jacobian", "fingertip_state"]

PEER_JOINTS = (3, 4, 7, 12)  #: joints of the benchmarked fingers
TARGET_RATIO = 1.0  #: pycapacity's time over mjtvm's: at least as fast
TRANSLATIONS = np.vstack([np.eye(6)[:3], -np.eye(6)[:3]])  #: the RVDS of the translations


def fingertip_jacobian(joints: int, seed: int = 0) -> NDArray[np.float64]:
    """``(3, joints)`` the fingertip's linear Jacobian of a seeded random spatial chain of
    revolute joints: unit axes ``z_i`` at points ``p_i`` 30-60 mm apart, columns
    $z_i \\times (p_{tip} - p_i)$ (m/rad)."""
    rng = np.random.default_rng(seed)
    axes = rng.normal(size=(joints, 3))
    axes /= np.linalg.norm(axes, axis=1, keepdims=True)
    steps = rng.normal(size=(joints + 1, 3))
    steps *= rng.uniform(0.03, 0.06, size=(joints + 1, 1)) / np.linalg.norm(steps, axis=1, keepdims=True)
    points = np.cumsum(steps, axis=0)
    return np.cross(axes, points[-1] - points[:-1]).T


def fingertip_state(joints: int, seed: int = 0) -> GraspState:
    """One F-contact at the tip of [`fingertip_jacobian()`][benchmarks.peers.fingertip_jacobian]'s chain, REFS = {0}, no gravity
    torque, the paper's motor ([`default_operation_range()`][mjtvm.model.operation_range.default_operation_range]) at
    every joint, the translations as RVDS: its TVMS is the fingertip's velocity polytope."""
    jac = fingertip_jacobian(joints, seed)
    tip = np.array([0.0, 0.0, -0.02])
    contact = Contact("tip", "F", tip, np.array([0.0, 0.0, 1.0]), jac, mu=0.5)
    return GraspState(
        space=3,
        object_position=np.zeros(3),
        joint_names=tuple(f"j{i}" for i in range(joints)),
        operation_ranges=(default_operation_range(),) * joints,
        gravity_torque=np.zeros(joints),
        contacts=(contact,),
        refs=np.zeros((1, 6)),
        rvds=TRANSLATIONS,
    )


def _pycapacity() -> Any:
    """``pycapacity.robot``, or ``None`` when it is not installed (it imports numpy.matlib, which
    warns: silenced)."""
    import warnings

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", PendingDeprecationWarning)
            import pycapacity.robot as robot
    except ImportError:
        return None
    return robot


def _pair(ours: Callable[[], object], theirs: Callable[[], object] | None, repeats: int) -> dict[str, Any]:
    """Medians of ``ours`` and ``theirs`` timed in alternation (who goes first alternates too),
    after one untimed call each; ``ratio`` = theirs / ours."""
    ours()
    if theirs is not None:
        theirs()
    a: list[float] = []
    b: list[float] = []
    for i in range(max(repeats, 1)):
        order = [(ours, a), (theirs, b)] if i % 2 == 0 else [(theirs, b), (ours, a)]
        for fn, out in order:
            if fn is None:
                continue
            t0 = time.perf_counter()
            fn()
            out.append(time.perf_counter() - t0)
    med_a = statistics.median(a)
    med_b = statistics.median(b) if b else None
    return {
        "ours_s": med_a,
        "peer_s": med_b,
        "ratio": None if med_b is None else med_b / med_a,
        "repeats": len(a),
    }


def _agreement(ours: NDArray[np.float64], other: NDArray[np.float64]) -> dict[str, Any]:
    """Hausdorff distance relative to the extent, and the vertex counts (``other``'s repeats merged)."""
    extent = float(np.max(np.abs(ours)))
    return {
        "hausdorff_rel": hausdorff(ours, other) / extent,
        "vertices": len(ours),
        "peer_vertices": len(distinct(other, 1e-9 * extent)),
    }


def _quiet(fn: Callable[[], Any]) -> Callable[[], Any]:
    """``fn`` with its stdout silenced (pycapacity prints when Qhull needs a retry)."""
    import contextlib
    import io

    def run() -> Any:
        with contextlib.redirect_stdout(io.StringIO()):
            return fn()

    return run


def _finger(joints: int, repeats: int, lp_repeats: int, robot: Any) -> dict[str, Any]:
    """The rows of one finger (module docstring)."""
    state = fingertip_state(joints)
    jac = state.contacts[0].jacobian
    top = np.array([r.max_speed for r in state.operation_ranges])
    torque = np.array([r.max_torque for r in state.operation_ranges])
    result = tvms(state)
    lp = tvms(state, method="lp")
    lp_times = []
    for _ in range(max(lp_repeats, 1)):
        t0 = time.perf_counter()
        tvms(state, method="lp")
        lp_times.append(time.perf_counter() - t0)
    velocity = _quiet(lambda: robot.velocity_polytope(jac, top, -top)) if robot else None
    force = _quiet(lambda: robot.force_polytope(jac, torque, -torque)) if robot else None
    row: dict[str, Any] = {
        "joints": joints,
        "method": result.method,
        "vertices": len(result.vertices),
        "affine_volume": result.affine_volume,
        "tvms": _pair(lambda: tvms(state), velocity, repeats),
        "function": _pair(lambda: velocity_polytope(jac, -top, top), velocity, repeats),
        "force": _pair(lambda: force_polytope(jac, -torque, torque), force, repeats),
        "lp": {
            "median_s": statistics.median(lp_times),
            "repeats": len(lp_times),
            "num_lps": lp.timings.num_lps,
        },
        "vs_lp": _agreement(result.vertices[:, :3], lp.vertices[:, :3]),
        "vs_peer": None,
        "force_vs_peer": None,
    }
    if velocity is not None and force is not None:
        row["vs_peer"] = _agreement(result.vertices[:, :3], np.asarray(velocity().vertices).T)
        row["force_vs_peer"] = _agreement(
            force_polytope(jac, -torque, torque).vertices, np.asarray(force().vertices).T
        )
    return row


def _own_example(repeats: int, robot: Any) -> dict[str, Any]:
    """pycapacity's four-link planar robot (2 x 4 Jacobian) at its documented posture, unit limits."""
    q = np.array([0.0, np.pi / 2, np.pi / 3, -np.pi / 2])
    if robot is not None:
        from pycapacity.examples import FourLinkRobot

        jac = np.asarray(FourLinkRobot().jacobian(q))
    else:  # the same Jacobian (pycapacity.examples.FourLinkRobot.jacobian), written out
        s = [np.sin(np.sum(q[: i + 1])) for i in range(4)]
        c = [np.cos(np.sum(q[: i + 1])) for i in range(4)]
        lengths = (0.5, 0.5, 0.5, 0.3)
        jac = np.array(
            [
                [sum(lengths[k] * c[k] for k in range(i, 4)) for i in range(4)],
                [-sum(lengths[k] * s[k] for k in range(i, 4)) for i in range(4)],
            ]
        )
    lim = np.ones(4)
    velocity = _quiet(lambda: robot.velocity_polytope(jac, lim, -lim)) if robot else None
    force = _quiet(lambda: robot.force_polytope(jac, lim, -lim)) if robot else None
    out: dict[str, Any] = {
        "jacobian": jac.tolist(),
        "velocity": _pair(lambda: velocity_polytope(jac, -lim, lim), velocity, repeats),
        "force": _pair(lambda: force_polytope(jac, -lim, lim), force, repeats),
    }
    if velocity is not None and force is not None:
        out["velocity_vs_peer"] = _agreement(
            velocity_polytope(jac, -lim, lim).vertices, np.asarray(velocity().vertices).T
        )
        out["force_vs_peer"] = _agreement(
            force_polytope(jac, -lim, lim).vertices, np.asarray(force().vertices).T
        )
    return out


def bench_peers(
    joints: Sequence[int] = PEER_JOINTS, *, repeats: int = 51, lp_repeats: int = 3
) -> dict[str, Any]:
    """Every measurement of the module docstring; JSON-ready, times in seconds."""
    robot = _pycapacity()
    try:
        version = importlib.metadata.version("pycapacity") if robot is not None else None
    except importlib.metadata.PackageNotFoundError:
        version = None
    rows = {str(n): _finger(n, repeats, lp_repeats, robot) for n in joints}
    example = _own_example(repeats, robot)
    met = None
    if robot is not None:
        met = all(
            r[k]["ratio"] >= TARGET_RATIO for r in rows.values() for k in ("tvms", "function", "force")
        ) and all(example[k]["ratio"] >= TARGET_RATIO for k in ("velocity", "force"))
    return {
        "peer": "pycapacity",
        "peer_version": version,
        "target_ratio": TARGET_RATIO,
        "met": met,
        "fingers": rows,
        "four_link_example": example,
    }
