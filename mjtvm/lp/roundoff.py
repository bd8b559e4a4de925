r"""Round-off: which coefficients of a state are exact zeros written inexactly.

A state written by any tool (MuJoCo, finite differences, another kinematics library, a
rotation of the frame) carries entries like ``1e-18`` where the exact value is 0. They are
not harmless: in an F-point's kinematic row of a planar finger, ``0 = v_y`` becomes
``1e-18 qd_0 = v_y``, which pins ``qd_0`` to 0 and the grasp's TVMMP with it (the exact LP
of the perturbed data has alpha 0). So the LPs are built on the data with its round-off
set to 0, by two rules (one constant, `DROP_REL`):

* **data** ([`drop_data_roundoff()`][mjtvm.lp.roundoff.drop_data_roundoff]): an entry of a contact Jacobian at most
  ``DROP_REL`` times the scale of the state's contact Jacobians, their largest entry (a joint that does
  not move the contact, written as noise of 1e-14 beside finger entries of 0.1, is 0; so is
  a 1e-18 in a row of zeros of a planar finger, and the noise in the Jacobian of a table
  that no joint moves). The entries of the Jacobians share their units (m/rad, or m/m for
  a prismatic joint), so the rule holds in any unit system; relative to a row, a column or
  one contact alone it would not see a 1e-18 in an empty row of an empty column, or a
  support's Jacobian of noise only. A component of a vector (a contact's normal, when the
  contact is built; its position relative to the object; an RVDS vertex) at most
  ``DROP_REL`` times its largest component is 0 too;
* **computation** ([`drop_cancellation()`][mjtvm.lp.roundoff.drop_cancellation]): a computed value at most ``DROP_REL`` times
  the sum of the magnitudes of the terms it was computed from (``n . (r x n)``, the
  tangent ``n x t1``, ``A_twist r``), however small the terms are in the state's units.

The largest entry of the Jacobians is their scale only when no gap sets it apart from the bulk
([`jacobian_scale()`][mjtvm.lp.roundoff.jacobian_scale]): a coefficient of 1e12 among lever arms of 0.1 m (within
the format's bounds) is data, but it is not what the other entries were computed from,
and relative to it every lever arm of the hand (0.1 < 1e-12 x 1e12) would be "round-off".

Both rules are relative, so a state in any unit system keeps every genuine coefficient,
however small. The right-hand sides (gravity torques, REFS) are left as written: a tiny
bound moves the answer continuously, a tiny coefficient does not. Noise larger than
``DROP_REL`` relative (a finite-difference Jacobian's 1e-8) is data: such a state should
be cleaned by its writer.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

__all__ = [
    "DROP_REL",
    "LONE_ENTRY",
    "OUTLIER_COUNT",
    "OUTLIER_SHARE",
    "cancelling_product",
    "drop_cancellation",
    "drop_data_roundoff",
    "jacobian_scale",
]

#: Round-off, relative: see the module docstring; also the equilibrated LP's rule
#: ([`scale_lp()`][mjtvm.lp.scaling.scale_lp]).
DROP_REL = 1e-12
#: How far the largest Jacobian entry may stand above the second largest and still be the
#: Jacobians' scale ([`jacobian_scale()`][mjtvm.lp.roundoff.jacobian_scale]). In the shipped states the two are within 1.3;
#: an entry alone far above the others is capped at 10 times the second largest, so that
#: every entry above DROP_REL times the others is kept, and the round-off of a real state
#: (1e-16 of its largest entry) is dropped as long as its two largest are within 1e4.
LONE_ENTRY = 10.0
#: How many of a state's largest non-zero Jacobian entries may stand as outliers above a gap
#: of ``LONE_ENTRY`` ([`jacobian_scale()`][mjtvm.lp.roundoff.jacobian_scale]): at most
#: ``OUTLIER_COUNT`` and at most ``OUTLIER_SHARE`` of them. Few, because the other reading of
#: the same numbers, a few lever arms above many round-off entries (a state whose zeros carry
#: 1e-17 noise), has as many large entries as the hand has lever arms.
OUTLIER_COUNT = 3
OUTLIER_SHARE = 0.25


def drop_cancellation(values: NDArray[np.float64], magnitudes: NDArray[np.float64]) -> NDArray[np.float64]:
    """``values`` with every entry at most ``DROP_REL * magnitudes`` set to 0, in place
    (and returned): ``magnitudes`` is, per entry, the sum of the magnitudes of the terms
    the value was computed from (``|a| @ |b|`` for ``a @ b``)."""
    values[np.abs(values) <= DROP_REL * magnitudes] = 0.0
    return values


def cancelling_product(a: NDArray[np.float64], b: NDArray[np.float64]) -> NDArray[np.float64]:
    """``a @ b`` with the round-off of exact cancellations set to 0, e.g. ``n . (r x n)``.

    Parameters
    ----------
    a, b
        Two matrices (or a matrix and a vector) whose product is taken.

    Returns
    -------
    NDArray[np.float64]
        ``a @ b`` through [`drop_cancellation()`][mjtvm.lp.roundoff.drop_cancellation] with
        the magnitudes ``|a| @ |b|``.
    """
    return drop_cancellation(a @ b, np.abs(a) @ np.abs(b))


def drop_data_roundoff(data: NDArray[np.float64], reference: float | None = None) -> NDArray[np.float64]:
    """A copy of ``data`` (entries sharing one unit, such as contact Jacobians) with every
    entry at most ``DROP_REL * reference`` in magnitude set to 0.

    Parameters
    ----------
    data
        Any shape.
    reference
        The magnitude the round-off is relative to; default the largest of ``data``.

    Returns
    -------
    ndarray
        Same shape; the input is not modified.
    """
    out = np.array(data, dtype=float)
    mag = np.abs(out)
    ref = float(mag.max(initial=0.0)) if reference is None else float(reference)
    out[mag <= DROP_REL * ref] = 0.0
    return out


def jacobian_scale(jacobians: list[NDArray[np.float64]]) -> float:
    """The scale of a state's contact Jacobians: their largest magnitude, or ``LONE_ENTRY``
    times the largest entry below a few outliers (the reference of their round-off,
    [`drop_data_roundoff()`][mjtvm.lp.roundoff.drop_data_roundoff], and of the certificate's contact speeds).

    A lever arm is computed from the robot's geometry, as are its round-off and every other
    lever arm: entries more than ``LONE_ENTRY`` times all the others (one or two coefficients
    of 1e12 in a hand of 0.1 m) were not, and taken as the scale they would make the hand's
    lever arms round-off (the LP would lose them and its alphas with them). Outliers are the
    entries above the deepest gap of more than ``LONE_ENTRY`` between consecutive magnitudes
    among the largest ``OUTLIER_COUNT`` (and at most a quarter, ``OUTLIER_SHARE``) of the
    non-zero entries: a few entries can be set aside, so the bulk of the lever arms sets the scale.
    Equal to the largest magnitude when there is no such gap, as in every real state.

    Parameters
    ----------
    jacobians
        Each ``(d, M)``, sharing their units (m/rad, m/m).

    Returns
    -------
    float
        0 when every entry is 0.
    """
    mags = np.concatenate([np.abs(np.ravel(j)) for j in jacobians]) if jacobians else np.zeros(0)
    mags = np.sort(mags[mags > 0.0])[::-1]
    if mags.size < 2:
        return float(mags.max(initial=0.0))
    top = max(1, min(OUTLIER_COUNT, int(OUTLIER_SHARE * mags.size)))  # candidates: mags[:top]
    gaps = np.flatnonzero(mags[:top] > LONE_ENTRY * mags[1 : top + 1])
    if gaps.size == 0:
        return float(mags[0])
    return float(LONE_ENTRY * mags[gaps[-1] + 1])
