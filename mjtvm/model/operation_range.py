r"""Operation ranges: the joint torque-velocity pair set (TVS) of one joint, eq. (1)-(3).

An operation range is a convex polygon $P$ in the quadrant of absolute joint
torque and absolute joint speed, $(|\tau|, |\dot q|)$ in (N m, rad/s), with a
vertex at the origin and one on each axis (paper, eq. 1). mjtvm additionally
requires $P$ to be *down-closed* (if $(a, b) \in P$ then every
$(a', b')$ with $0 \le a' \le a$, $0 \le b' \le b$ is too), which
holds for every motor operation range: only then is the box of eq. (2) exactly the
operation range (see [`mirrored_halfplanes()`][mjtvm.model.polygon.mirrored_halfplanes]).
"""

from __future__ import annotations

import functools
import itertools
import json
from dataclasses import dataclass, field
from functools import cached_property
from importlib import resources
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from mjtvm.errors import StateError
from mjtvm.model.polygon import halfplanes, mirrored_halfplanes, validated_vertices

__all__ = ["OperationRange", "default_operation_range", "load_motor_data"]

_RPM = 2.0 * np.pi / 60.0  # rad/s per rpm

#: Distinct vertex arrays whose validation `OperationRange` keeps (least recently used out).
VALIDATED_CACHE_SIZE = 4096


def _validate(raw: object) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The checked vertices and the off-axis half-planes, both read only (shared by every
    range of the same vertices: what is derived from them is cached)."""
    v, u, scale = validated_vertices(raw)
    v = v.copy()
    v.setflags(write=False)
    hp = halfplanes(u, scale)
    hp.setflags(write=False)
    return v, hp


@functools.lru_cache(maxsize=VALIDATED_CACHE_SIZE)
def _validated(data: bytes, shape: tuple[int, ...]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """`_validate()` of the float64 array of these bytes and shape (a failure is not kept:
    it raises again on every call)."""
    return _validate(np.frombuffer(data, dtype=np.float64).reshape(shape))


@functools.lru_cache(maxsize=VALIDATED_CACHE_SIZE)
def _net_vertices(
    data: bytes, shape: tuple[int, ...], damping: float, friction: float
) -> NDArray[np.float64]:
    """`OperationRange.with_losses()`'s vertices for the vertices of these bytes and shape
    (cached: a batch folds the same few ranges' losses for every grasp)."""
    vertices = np.frombuffer(data, dtype=np.float64).reshape(shape)
    chain = vertices[np.any(vertices != 0.0, axis=1)]
    chain = chain[np.lexsort((-chain[:, 0], chain[:, 1]))]  # (T, 0) first, (0, w0) last
    net = chain - np.column_stack([damping * chain[:, 1] + friction, np.zeros(len(chain))])
    if net[0, 0] <= 0.0:
        raise StateError(
            "friction", f"friction loss {friction:g} N m leaves no torque of {net[0, 0] + friction:g}"
        )
    kept = [net[0]]
    for a, b in itertools.pairwise(net):
        if b[0] > 0.0:
            kept.append(b)
            continue
        w = a[1] + (b[1] - a[1]) * a[0] / (a[0] - b[0])  # where the net torque reaches 0
        kept.append(np.array([0.0, w]))
        break  # the last vertex, (-d w0 - f, w0), always has a negative net torque: reached
    out = np.vstack([[0.0, 0.0], *kept])
    out.setflags(write=False)
    return out


@dataclass(frozen=True, eq=False)
class OperationRange:
    r"""A validated operation range $P$ of one joint (paper, eq. 1).

    Parameters
    ----------
    vertices
        ``(n, 2)`` polygon vertices ``[|tau| (N m), |qdot| (rad/s)]`` in boundary order
        (either orientation). Must be finite, non-negative, convex, contain the origin
        as a vertex, have a vertex on each axis and be down-closed: the largest torque
        is reached at zero speed and the largest speed at zero torque.

    Raises
    ------
    StateError
        Naming the problem (field ``""``; callers prefix the field path).
    """

    vertices: NDArray[np.float64]
    _halfplanes: NDArray[np.float64] = field(init=False, repr=False)

    def __post_init__(self) -> None:
        raw = self.vertices
        if isinstance(raw, np.ndarray) and raw.dtype == np.float64 and raw.ndim == 2:
            # A batch builds the same few ranges for every grasp and every diagnosis
            # relaxation: validated once per exact vertex array (its bytes and shape).
            v, hp = _validated(raw.tobytes(), raw.shape)
        else:
            v, hp = _validate(raw)
        object.__setattr__(self, "vertices", v)
        object.__setattr__(self, "_halfplanes", hp)

    # ------------------------------------------------------------------ views
    @cached_property
    def max_torque(self) -> float:
        """Largest absolute torque (N m), reached at zero speed."""
        return float(np.max(self.vertices[:, 0]))

    @cached_property
    def max_speed(self) -> float:
        """Largest absolute speed (rad/s), reached at zero torque."""
        return float(np.max(self.vertices[:, 1]))

    @property
    def halfplanes(self) -> NDArray[np.float64]:
        r"""``(h, 3)`` rows ``[a_tau, a_qd, b]``: $P = \{x \ge 0 : a^T x \le b\}$.

        Only the edges off the axes are listed (the axis edges are $x \ge 0$);
        every ``a`` is non-negative and every ``b`` positive because $P$ is
        down-closed.
        """
        return self._halfplanes

    @cached_property
    def mirrored_halfplanes(self) -> NDArray[np.float64]:
        r"""``(h', 3)`` rows ``[c_tau, c_qd, b]`` with $(\tau, \dot q)$ feasible iff
        $c_\tau \tau + c_{qd} \dot q \le b$ for every row.

        This is the exact elimination of the four box variables of eq. (2).

        **Claim.** For a convex, down-closed $P$, a signed pair
        $(\tau, \dot q)$ admits a box
        $\tau_{min} \le \tau \le \tau_{max}$, $\dot q_{min} \le \dot q \le
        \dot q_{max}$ whose four corners lie in the copies of $P$ mirrored into
        their quadrants (eq. 2) if and only if $(|\tau|, |\dot q|) \in P$, i.e. iff
        $s_1 a_\tau \tau + s_2 a_{qd} \dot q \le b$ for every edge
        $a^T x \le b$ of $P$ off the axes and every
        $s_1, s_2 \in \{-1, 1\}$.

        **Proof.** (if) Take $\tau_{max} = \max(\tau, 0)$,
        $\tau_{min} = \min(\tau, 0)$ and likewise for $\dot q$. Each corner's
        absolute value is componentwise at most $(|\tau|, |\dot q|) \in P$, so it
        lies in $P$ by down-closure. (only if) The corner of the box in the
        quadrant of $(\tau, \dot q)$ dominates $(|\tau|, |\dot q|)$
        componentwise and lies in $P$ (mirrored back); down-closure puts
        $(|\tau|, |\dot q|)$ in $P$. Finally, $x \in \mathbb{R}^2_{\ge 0}$
        lies in $P$ iff $a^T x \le b$ on its off-axis edges, and as every
        $a \ge 0$, $a^T |x| \le b$ is equivalent to the four sign
        combinations, all linear. With several REFS vertices sharing one box
        (eq. 26) the same argument gives $(|\tau_i|, |\dot q|) \in P$ for every
        vertex i. QED.
        """
        return mirrored_halfplanes(self._halfplanes)

    def contains(self, torque: float, speed: float, *, tol: float = 1e-9) -> bool:
        r"""Whether $(|\tau|, |\dot q|)$ lies in $P$ (with slack ``tol``)."""
        x = np.array([abs(torque), abs(speed)])
        return bool(np.all(self._halfplanes[:, :2] @ x <= self._halfplanes[:, 2] + tol))

    def max_speed_at(self, torque: float) -> float:
        r"""Largest $|\dot q|$ available at torque $|\tau|$ (rad/s); ``-inf``
        when $|\tau|$ exceeds the maximum torque."""
        t = abs(torque)
        if t > self.max_torque * (1 + 1e-12):
            return float("-inf")
        best = self.max_speed
        for a_t, a_q, b in self._halfplanes:
            if a_q > 0.0:
                best = min(best, (b - a_t * t) / a_q)
        return float(best)

    def scaled(self, *, torque: float = 1.0, speed: float = 1.0) -> OperationRange:
        """A copy with torque and speed coordinates multiplied by positive factors."""
        return OperationRange(self.vertices * np.array([torque, speed]))

    def with_losses(self, *, damping: float = 0.0, friction: float = 0.0) -> OperationRange:
        r"""The range of the torque left at the joint after viscous damping and dry friction.

        The joint's torque balance (eq. 19) gains the passive torque of the joint:
        $\tau_{motor} = \tau + d\,\dot q + f\,\mathrm{sgn}(\dot q)$ with damping
        ``d`` (N m s/rad) and friction loss ``f`` (N m), MuJoCo's ``dof_damping`` and
        ``dof_frictionloss``. Requiring $|\tau| + d|\dot q| + f \le T(|\dot q|)$
        (``T`` this range's torque at a speed) maps every vertex $(t, w)$ to
        $(t - d w - f, w)$ and clips at $t = 0$: a convex, down-closed polygon
        again. It is exact while the motor drives (torque and speed of one sign) and
        conservative while it brakes, where the losses would help: the operation range is one
        polygon for all four sign quadrants (eq. 2).

        Raises
        ------
        StateError
            Negative or non-finite losses, or a friction loss that leaves no torque.
        """
        for name, value in (("damping", damping), ("friction", friction)):
            if not (np.isfinite(value) and value >= 0):
                raise StateError(name, f"expected a finite number >= 0, got {value!r}")
        if damping == 0.0 and friction == 0.0:
            return self
        v = self.vertices
        return OperationRange(_net_vertices(v.tobytes(), v.shape, float(damping), float(friction)))

    def to_list(self) -> list[list[float]]:
        """The vertices as a JSON-ready list."""
        return [[float(a), float(b)] for a, b in self.vertices]

    # ------------------------------------------------------------ constructors
    @classmethod
    def box(cls, torque: float, speed: float) -> OperationRange:
        """The box ``|tau| <= torque, |qd| <= speed`` (N m, rad/s; or an actuator's units)."""
        return cls(np.array([[0.0, 0.0], [torque, 0.0], [torque, speed], [0.0, speed]]))

    @classmethod
    def from_datasheet(
        cls,
        *,
        no_load_speed_rpm: float,
        nominal_speed_rpm: float,
        nominal_torque_mNm: float,
        max_permissible_speed_rpm: float,
        gear_ratio: float = 1.0,
        gear_efficiency: float = 1.0,
    ) -> OperationRange:
        r"""Continuous-operation range of a DC motor behind a gear, at the joint.

        maxon's operating-range diagram: the region under the speed-torque line at
        nominal voltage (through the no-load point and the nominal point), left of the
        max continuous torque (the nominal torque, a thermal limit) and below the max
        permissible speed. The joint sees torque x ``gear_ratio`` x ``gear_efficiency``
        and speed / ``gear_ratio``.

        Parameters
        ----------
        no_load_speed_rpm, nominal_speed_rpm
            Motor speeds (rpm) at zero torque and at the nominal torque.
        nominal_torque_mNm
            Max continuous torque of the motor (mN m).
        max_permissible_speed_rpm
            Mechanical speed limit of the motor (rpm).
        gear_ratio
            Motor turns per joint turn (40 for the paper's 1/40 gear).
        gear_efficiency
            In (0, 1]; scales the torque coordinates only.

        Returns
        -------
        OperationRange
            Vertices in (N m, rad/s) at the joint.
        """
        figures = {
            "no_load_speed_rpm": no_load_speed_rpm,
            "nominal_speed_rpm": nominal_speed_rpm,
            "nominal_torque_mNm": nominal_torque_mNm,
            "max_permissible_speed_rpm": max_permissible_speed_rpm,
            "gear_ratio": gear_ratio,
        }
        for name, value in figures.items():
            if not (np.isfinite(value) and value > 0):
                raise StateError(name, f"expected a positive finite number, got {value!r}", value)
        if not (0.0 < gear_efficiency <= 1.0):
            raise StateError("gear_efficiency", f"expected a number in (0, 1], got {gear_efficiency!r}")
        if nominal_speed_rpm >= no_load_speed_rpm:
            raise StateError(
                "nominal_speed_rpm",
                f"must be below the no-load speed {no_load_speed_rpm} rpm, got {nominal_speed_rpm}",
            )
        slope = (no_load_speed_rpm - nominal_speed_rpm) / nominal_torque_mNm  # rpm per mNm
        torque = nominal_torque_mNm * 1e-3 * gear_ratio * gear_efficiency  # N m at the joint
        to_joint = _RPM / gear_ratio
        verts = [[0.0, 0.0], [torque, 0.0]]
        if max_permissible_speed_rpm <= nominal_speed_rpm:
            verts += [[torque, max_permissible_speed_rpm * to_joint]]
            verts += [[0.0, max_permissible_speed_rpm * to_joint]]
        else:
            verts += [[torque, nominal_speed_rpm * to_joint]]
            if max_permissible_speed_rpm < no_load_speed_rpm:
                knee = (no_load_speed_rpm - max_permissible_speed_rpm) / slope  # mNm
                scale = torque / nominal_torque_mNm
                verts += [[knee * scale, max_permissible_speed_rpm * to_joint]]
                verts += [[0.0, max_permissible_speed_rpm * to_joint]]
            else:
                verts += [[0.0, no_load_speed_rpm * to_joint]]
        return cls(np.array(verts))


def load_motor_data(name: str = "maxon_re25_20w") -> dict[str, Any]:
    """The datasheet figures shipped in ``mjtvm/data/<name>.json`` (with their source)."""
    text = resources.files("mjtvm.data").joinpath(f"{name}.json").read_text(encoding="utf-8")
    data: dict[str, Any] = json.loads(text)
    return data


def default_operation_range(*, gear_efficiency: float | None = None) -> OperationRange:
    r"""The paper's actuator: maxon RE25 20 W behind a 1/40 gear (Fig. 1).

    With the shipped figures this is the polygon (0, 0), (1.052, 0), (1.052, 21.81),
    (0, 25.03) in (N m, rad/s): the max permissible speed (14000 rpm) lies above the
    no-load speed, so it does not cut the polygon.
    """
    m = load_motor_data()
    return OperationRange.from_datasheet(
        no_load_speed_rpm=m["no_load_speed_rpm"],
        nominal_speed_rpm=m["nominal_speed_rpm"],
        nominal_torque_mNm=m["nominal_torque_mNm"],
        max_permissible_speed_rpm=m["max_permissible_speed_rpm"],
        gear_ratio=m["gear_ratio"],
        gear_efficiency=m["gear_efficiency"] if gear_efficiency is None else gear_efficiency,
    )


def as_operation_range(value: OperationRange | ArrayLike) -> OperationRange:
    """Coerce vertices (or an existing range) to an `OperationRange`."""
    return value if isinstance(value, OperationRange) else OperationRange(np.asarray(value))
