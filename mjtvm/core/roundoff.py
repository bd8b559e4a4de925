r"""Round-off: which coefficients of a state are exact zeros written inexactly.

A state written by any tool (MuJoCo, finite differences, another kinematics library, a
rotation of the frame) carries entries like ``1e-18`` where the exact value is 0. They are
not harmless: in an F-point's kinematic row of a planar finger, ``0 = v_y`` becomes
``1e-18 qd_0 = v_y``, which pins ``qd_0`` to 0 and the grasp's TVMMP with it (the exact LP
of the perturbed data has alpha 0). So the LPs are built on the data with its round-off
set to 0, by two rules (one constant, :data:`DROP_REL`):

* **data** (:func:`drop_data_roundoff`): an entry of a contact Jacobian at most
  ``DROP_REL`` times the largest entry of the state's contact Jacobians (a joint that does
  not move the contact, written as noise of 1e-14 beside finger entries of 0.1, is 0; so is
  a 1e-18 in a row of zeros of a planar finger, and the noise in the Jacobian of a table
  that no joint moves). The entries of the Jacobians share their units (m/rad, or m/m for
  a prismatic joint), so the rule holds in any unit system; relative to a row, a column or
  one contact alone it would not see a 1e-18 in an empty row of an empty column, or a
  support's Jacobian of noise only. A component of a vector (a contact's normal, when the
  contact is built; its position relative to the object; an RVDS vertex) at most
  ``DROP_REL`` times its largest component is 0 too;
* **computation** (:func:`drop_cancellation`): a computed value at most ``DROP_REL`` times
  the sum of the magnitudes of the terms it was computed from (``n . (r x n)``, the
  tangent ``n x t1``, ``A_twist r``), however small the terms are in the state's units.

Both rules are relative, so a state in any unit system keeps every genuine coefficient,
however small. The right-hand sides (gravity torques, REFS) are left as written: a tiny
bound moves the answer continuously, a tiny coefficient does not. Noise larger than
``DROP_REL`` relative (a finite-difference Jacobian's 1e-8) is data: such a state should
be cleaned by its writer.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

__all__ = ["DROP_REL", "drop_cancellation", "drop_data_roundoff"]

#: Round-off, relative: see the module docstring; also the equilibrated LP's rule
#: (:func:`~mjtvm.core.scaling.scale_lp`).
DROP_REL = 1e-12


def drop_cancellation(values: NDArray[np.float64], magnitudes: NDArray[np.float64]) -> NDArray[np.float64]:
    """``values`` with every entry at most ``DROP_REL * magnitudes`` set to 0, in place
    (and returned): ``magnitudes`` is, per entry, the sum of the magnitudes of the terms
    the value was computed from (``|a| @ |b|`` for ``a @ b``)."""
    values[np.abs(values) <= DROP_REL * magnitudes] = 0.0
    return values


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
