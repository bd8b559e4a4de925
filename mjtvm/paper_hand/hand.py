r"""The paper's four-finger hand and its sphere as a MuJoCo model (MJCF), section 5, Fig. 4.

[`hand_mjcf()`][mjtvm.paper_hand.hand.hand_mjcf] writes the model; ``models/paper_hand/*.xml`` are its committed output
(``tools/make_models.py``). [`operation_range_from_actuator()`][mjtvm.grasp.actuation.actuator.operation_range_from_actuator] reads a joint's
operation range back from the compiled ``<dcmotor>``: the MJCF is the single source of truth.

Geometry (world frame, m). Palm: the plane z = 0 (geom ``palm``). Finger i (``f1`` ... ``f4``)
starts at ``FINGER_BASES[i]``, its base frame turned by ``FINGER_HEADINGS[i]`` about +z; at
zero joint angles it lies straight on the palm along that frame's +x. Each link is a capsule
along its body's +x; a fingertip sphere ``f<i>_tip`` ends the last link. Joint axes in the link
frames: ``yaw`` +z, ``pitch`` -y (a positive pitch lifts the link: flexion), ``roll`` +x. Joints
at one site apply in the order listed, so in ``("pitch", "yaw")`` the yaw axis turns with the
pitch and stays perpendicular to link 2.

Headings. Fingers 2-4 point to +x: in Case 1 finger 3's link 1 lies on the palm from x = 0.05
to 0.15 and its contact [0.171 0 0.072] lies beyond, on the sphere's +x side, reached with the
second pitch at atan2(0.072, 0.021) = 73.7 deg and every other joint at 0. Finger 1 opposes
them (its contacts are on the sphere's -x side), so it is turned by 180 deg and points to -x.
Flexion then turns every finger's palmar side (+z of the straight link) towards the object,
and the paper's contacts need pitches up to about 180 deg and yaws within +-90 deg.

Actuators: one ``<dcmotor>`` per joint, named like it (`DCMotor`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from mjtvm.errors import ModelError
from mjtvm.grasp.actuation.dcmotor import DCMotor
from mjtvm.grasp.actuation.dcmotor import mjcf_numbers as _fmt

__all__ = [
    "DEFAULT_FINGER_JOINTS",
    "FINGER_BASES",
    "FINGER_HEADINGS",
    "GRAVITY",
    "HUMANLIKE_FINGER_JOINTS",
    "JOINT_AXES",
    "JOINT_RANGES",
    "finger_joint_names",
    "hand_mjcf",
    "model_files",
]

FingerJoints = Sequence[Sequence[str]]
DEFAULT_FINGER_JOINTS: tuple[tuple[str, ...], ...] = (("yaw", "pitch"), ("pitch", "yaw"))
"""2-DOF joints [yaw, pitch] at the finger base and [pitch, yaw] at the end of link 1; two links."""
HUMANLIKE_FINGER_JOINTS: tuple[tuple[str, ...], ...] = (("yaw", "pitch"), ("pitch",), ("pitch",))
"""Yaw + pitch at the base, then two pitches; three links."""
FINGER_BASES = ((-0.1, -0.05, 0.0), (0.05, 0.1, 0.0), (0.05, 0.0, 0.0), (0.05, -0.1, 0.0))
FINGER_HEADINGS: tuple[float, ...] = (math.pi, 0.0, 0.0, 0.0)
"""Rotation of each finger's base frame about +z (rad): finger 1 points to -x, the others to +x."""
JOINT_AXES: dict[str, tuple[float, float, float]] = {"yaw": (0, 0, 1), "pitch": (0, -1, 0), "roll": (1, 0, 0)}
JOINT_RANGES: dict[str, tuple[float, float]] = {
    "yaw": (-math.pi / 2, math.pi / 2),
    "pitch": (-math.pi / 2, math.pi),
    "roll": (-math.pi, math.pi),
}
GRAVITY = 9.81  # m/s^2


def _check_finger_joints(finger_joints: FingerJoints) -> tuple[tuple[str, ...], ...]:
    sites = tuple(tuple(site) for site in finger_joints)
    if not sites or any(not site for site in sites):
        raise ModelError("finger_joints", "expected one non-empty joint sequence per link")
    for k, site in enumerate(sites):
        for kind in site:
            if kind not in JOINT_AXES:
                raise ModelError(
                    "finger_joints", f"unknown joint kind {kind!r} (known: {', '.join(JOINT_AXES)})"
                )
        if len(set(site)) != len(site):
            raise ModelError("finger_joints", f"a joint kind repeats at site {k}: {site}")
    return sites


def finger_joint_names(finger: int, finger_joints: FingerJoints = DEFAULT_FINGER_JOINTS) -> list[str]:
    """Joint names of finger ``finger`` (1-based), base first: ``f1_yaw0``, ``f1_pitch0``, ..."""
    sites = _check_finger_joints(finger_joints)
    return [f"f{finger}_{kind}{k}" for k, site in enumerate(sites) for kind in site]


def hand_mjcf(
    *,
    finger_joints: FingerJoints = DEFAULT_FINGER_JOINTS,
    link_length: float = 0.1,
    link_mass: float = 0.051,
    capsule_radius: float = 0.004,
    tip_radius: float = 0.005,
    finger_bases: Sequence[Sequence[float]] = FINGER_BASES,
    finger_headings: Sequence[float] = FINGER_HEADINGS,
    object_radius: float = 0.1,
    mg: float = 1.0,
    object_position: Sequence[float] = (0.0, 0.0, 0.1),
    friction: float = 0.3,
    contact_gap: float = 0.001,
    motor: DCMotor | None = None,
    model_name: str = "four_finger_hand",
) -> str:
    r"""MJCF text of the hand, the palm and a free sphere.

    Long only through its signature and parameter documentation (one keyword per option);
    the body is a short sequence of the named steps below it in this module.

    Parameters
    ----------
    finger_joints
        Per link, the joint kinds (``"yaw"``, ``"pitch"``, ``"roll"``) at its start, in order;
        the number of links is its length. Joints are named ``f<i>_<kind><link index>``.
    link_length, link_mass
        Every link (m, kg); centre of mass at mid-link, thin-rod inertia.
    capsule_radius, tip_radius
        Radii of the link capsules and of the fingertip spheres (m). The tip is slightly
        larger than the capsule so that contacts near the finger end are the tip's.
    finger_bases, finger_headings
        ``(F, 3)`` base positions (m) and ``(F,)`` base rotations about +z (rad).
    object_radius
        Sphere radius (m).
    mg
        Object weight (N, g = 9.81): mass ``mg / g``. With ``mg = 0`` the sphere keeps a
        mass of 1/g kg and full gravity compensation (``gravcomp="1"``), so it weighs nothing.
    object_position
        ``(3,)`` initial sphere centre (m).
    friction
        Sliding friction coefficient of every geom (simulation only; the TVM takes its own mu).
    contact_gap
        MuJoCo 4 ``gap`` of the sphere (m): contacts up to this separation are reported in
        ``mjData.contact`` as inactive (no contact force), so that touching geoms are found.
    motor
        The actuator of every joint (default [`DCMotor.from_datasheet()`][mjtvm.grasp.actuation.dcmotor.DCMotor.from_datasheet]).
    model_name
        ``<mujoco model=...>``.

    Returns
    -------
    str
        The MJCF document.
    """
    sites = _check_finger_joints(finger_joints)
    bases, headings = _check_hand(
        finger_bases,
        finger_headings,
        mg,
        link_length=link_length,
        link_mass=link_mass,
        capsule_radius=capsule_radius,
        tip_radius=tip_radius,
        object_radius=object_radius,
    )
    motor = DCMotor.from_datasheet() if motor is None else motor
    out = _header(model_name, motor, friction)
    actuators: list[str] = []
    for f, (base, heading) in enumerate(zip(bases, headings, strict=True), start=1):
        body, acts = _finger_bodies(
            f,
            base,
            float(heading),
            sites,
            motor,
            length=float(link_length),
            mass=float(link_mass),
            capsule_radius=capsule_radius,
            tip_radius=tip_radius,
        )
        out += body
        actuators += acts
    mass = mg / GRAVITY if mg > 0 else 1.0 / GRAVITY
    gravcomp = "" if mg > 0 else ' gravcomp="1"'
    out += [
        f'    <body name="object" pos="{_fmt(*object_position)}"{gravcomp}>',
        '      <freejoint name="object"/>',
        f'      <geom name="object" type="sphere" size="{_fmt(object_radius)}" mass="{_fmt(mass)}" '
        f'contype="1" conaffinity="2" gap="{_fmt(contact_gap)}" '
        'rgba="0.85 0.2 0.2 0.5"/>',
        "    </body>",
        "  </worldbody>",
        "  <actuator>",
        *actuators,
        "  </actuator>",
        "</mujoco>",
        "",
    ]
    return "\n".join(out)


def _check_hand(
    finger_bases: Sequence[Sequence[float]], finger_headings: Sequence[float], mg: float, **sizes: float
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The bases ``(F, 3)`` and headings ``(F,)`` of [`hand_mjcf()`][mjtvm.paper_hand.hand.hand_mjcf], its sizes positive, ``mg >= 0``."""
    bases = np.asarray(finger_bases, dtype=float)
    headings = np.asarray(finger_headings, dtype=float)
    if bases.ndim != 2 or bases.shape[1] != 3 or headings.shape != (bases.shape[0],):
        raise ModelError("finger_bases", "expected (F, 3) positions and F headings")
    for name, value in sizes.items():
        if not (math.isfinite(value) and value > 0):
            raise ModelError(name, f"expected a positive finite number, got {value!r}")
    if not (math.isfinite(mg) and mg >= 0):
        raise ModelError("mg", f"expected a finite weight >= 0 (N), got {mg!r}")
    return bases, headings


def _header(model_name: str, motor: DCMotor, friction: float) -> list[str]:
    """The MJCF up to the palm: compiler, options, geom defaults, light and palm plane."""
    return [
        f'<mujoco model="{model_name}">',
        "  <!-- Generated by mjtvm.paper_hand.hand.hand_mjcf (tools/make_models.py); do not edit by hand. -->",
        f"  <!-- Actuators: <dcmotor> {_fmt(motor.voltage)} V, stall {_fmt(motor.stall_torque)} N m, "
        f"no-load {_fmt(motor.no_load_speed)} rad/s, continuous {_fmt(motor.max_continuous_torque)} N m, "
        f"gear {_fmt(motor.gear)} (motor side). -->",
        '  <compiler angle="radian" autolimits="true"/>',
        f'  <option timestep="0.001" gravity="0 0 {_fmt(-GRAVITY)}" integrator="implicitfast"/>',
        "  <default>",
        f'    <geom contype="2" conaffinity="0" friction="{_fmt(friction)} 0.005 0.0001"/>',
        "  </default>",
        "  <worldbody>",
        '    <light pos="0 0 1.5" dir="0 0 -1" directional="true"/>',
        '    <geom name="palm" type="plane" size="0.4 0.4 0.01" rgba="0.75 0.75 0.7 1"/>',
    ]


def _finger_bodies(
    f: int,
    base: NDArray[np.float64],
    heading: float,
    sites: Sequence[Sequence[str]],
    motor: DCMotor,
    *,
    length: float,
    mass: float,
    capsule_radius: float,
    tip_radius: float,
) -> tuple[list[str], list[str]]:
    """Finger ``f``: its nested link bodies (joints, thin-rod inertia, capsule; the tip sphere on
    the last) and one actuator line per joint."""
    i_axial = 0.5 * mass * capsule_radius**2
    i_trans = mass * (3 * capsule_radius**2 + length**2) / 12.0
    out: list[str] = []
    actuators: list[str] = []
    indent = "    "
    quat = _fmt(math.cos(heading / 2), 0.0, 0.0, math.sin(heading / 2))
    for k, site in enumerate(sites):
        pos = _fmt(*base) if k == 0 else _fmt(length, 0, 0)
        orient = f' quat="{quat}"' if k == 0 else ""
        out.append(f'{indent}<body name="f{f}_link{k + 1}" pos="{pos}"{orient}>')
        indent += "  "
        for kind in site:
            name = f"f{f}_{kind}{k}"
            lo, hi = JOINT_RANGES[kind]
            axis = _fmt(*JOINT_AXES[kind])
            out.append(f'{indent}<joint name="{name}" type="hinge" axis="{axis}" range="{_fmt(lo, hi)}"/>')
            actuators.append("    " + motor.mjcf(name, name))
        out.append(
            f'{indent}<inertial pos="{_fmt(length / 2, 0, 0)}" mass="{_fmt(mass)}" '
            f'diaginertia="{_fmt(i_axial, i_trans, i_trans)}"/>'
        )
        out.append(
            f'{indent}<geom name="f{f}_link{k + 1}" type="capsule" fromto="0 0 0 {_fmt(length)} 0 0" '
            f'size="{_fmt(capsule_radius)}" rgba="0.3 0.45 0.8 1"/>'
        )
    out.append(
        f'{indent}<geom name="f{f}_tip" type="sphere" pos="{_fmt(length, 0, 0)}" '
        f'size="{_fmt(tip_radius)}" rgba="0.9 0.5 0.2 1"/>'
    )
    for _ in sites:
        indent = indent[:-2]
        out.append(f"{indent}</body>")
    return out, actuators


def model_files() -> dict[str, str]:
    """File name -> MJCF of the committed models in ``models/paper_hand/`` (default and human-like hands)."""
    return {
        "four_finger_hand.xml": hand_mjcf(),
        "four_finger_hand_humanlike.xml": hand_mjcf(
            finger_joints=HUMANLIKE_FINGER_JOINTS, model_name="four_finger_hand_humanlike"
        ),
    }
