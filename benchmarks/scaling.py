r"""Scaling in the benchmark suite: synthetic hands of 2 to 16 fingers ([`scaling_hand()`][benchmarks.scaling.scaling_hand]) and
the time and memory of Problems 1 and 2 on them ([`bench_scaling()`][benchmarks.scaling.bench_scaling]).
"""

from __future__ import annotations

import itertools
import math
import time
from collections.abc import Sequence
from typing import Any

import numpy as np

from benchmarks.measure import rss_mib, stats, times, traced_peak_mib
from mjtvm.errors import ModelError

__all__ = ["SCALING_FINGERS", "SCALING_RADIUS", "bench_scaling", "scaling_hand"]

SCALING_FINGERS = (2, 4, 8, 16)
SCALING_RADIUS = 0.12  # m: finger bases on this circle around the object's axis


def scaling_hand(fingers: int, *, mu: float = 0.5, mg: float = 1.0) -> Any:
    r"""A grasp state of a synthetic hand with ``fingers`` fingers of 4 joints (IK-free).

    The MJCF comes from [`hand_mjcf()`][mjtvm.paper_hand.hand.hand_mjcf] (default finger: [yaw, pitch] at the
    base, [pitch, yaw] after link 1): bases evenly on a circle of radius
    [`SCALING_RADIUS`][benchmarks.scaling.SCALING_RADIUS] around the z axis, headings pointing inwards. Every finger takes
    the same pose (link 1 vertical, link 2 pointing up and inwards at 54 deg), so all tips lie
    on one circle at one height; the sphere's centre is put on the axis where its surface
    touches every tip (0.1 mm deep). One F-contact per finger (the tip), friction ``mu``, REFS
    = the weight ``mg``, RVDS = the 4 vertices [+-1, +-1, 1, 0, 0, 0] of Case 2.
    """
    import mujoco

    from mjtvm.grasp.resolve.state import grasp_state
    from mjtvm.paper_hand.hand import hand_mjcf

    angles = 2 * math.pi * np.arange(fingers) / fingers
    bases = [(SCALING_RADIUS * math.cos(a), SCALING_RADIUS * math.sin(a), 0.0) for a in angles]
    headings = [float(a + math.pi) for a in angles]
    radius, tip = 0.1, 0.005
    xml = hand_mjcf(
        finger_bases=bases,
        finger_headings=headings,
        mg=mg,
        object_position=(0.0, 0.0, 10.0),
        model_name=f"scaling_{fingers}",
    )
    model = mujoco.MjModel.from_xml_string(xml)
    data = mujoco.MjData(model)
    for f in range(1, fingers + 1):
        data.joint(f"f{f}_pitch0").qpos[0] = math.pi / 2  # link 1 vertical
        data.joint(f"f{f}_pitch1").qpos[0] = math.radians(54.0) - math.pi / 2  # link 2 up, inwards
    mujoco.mj_kinematics(model, data)
    tip_pos = data.geom("f1_tip").xpos.copy()
    r_t, z_t = math.hypot(tip_pos[0], tip_pos[1]), tip_pos[2]
    reach = radius + tip - 1e-4
    z_c = z_t + math.sqrt(reach**2 - r_t**2)
    obj = model.joint("object").qposadr[0]
    data.qpos[obj : obj + 7] = [0.0, 0.0, z_c, 1.0, 0.0, 0.0, 0.0]
    rvds = np.array([[sx, sy, 1.0, 0, 0, 0] for sx in (1, -1) for sy in (1, -1)])
    state = grasp_state(
        model, data, contact_types={f"f{f}_tip": "F" for f in range(1, fingers + 1)}, mu=mu, rvds=rvds
    )
    if len(state.contacts) != fingers or any(c.name != f"f{i}_tip" for i, c in enumerate(state.contacts, 1)):
        raise ModelError(
            f"the {fingers}-finger hand",
            f"expected one tip contact per finger, got {[c.name for c in state.contacts]}",
        )
    return state


def _scale_one(fingers: int, repeats: int, p1_repeats: int) -> dict[str, Any]:
    from mjtvm.polytopes.tvms import tvms
    from mjtvm.problem2.tvmmp import tvmmp

    t0 = time.perf_counter()
    state = scaling_hand(fingers)
    build = time.perf_counter() - t0
    p2 = times(lambda: tvmmp(state, witnesses=False), repeats, warmup=3)
    big = fingers >= 16  # Problem 1 takes seconds there: fewer runs, no warm-up, no tracemalloc
    last: list[Any] = []
    p1 = times(
        lambda: last.append(tvms(state)),
        max(1, p1_repeats // 2) if big else p1_repeats,
        warmup=0 if big else 1,
    )
    p2_res = tvmmp(state, witnesses=False)
    from benchmarks.timing import highs_split

    split = highs_split(state, max(1, min(repeats, 50)), 1)
    return {
        "joints": state.num_joints,
        "contacts": len(state.contacts),
        "build_s": build,
        "tvmmp": p2_res.tvmmp,
        "num_lps": p2_res.timings.num_lps,
        "p2": stats(p2),
        "p2_highs_run_s": split["highs_run_s"],
        "p2_python_s": split["python_overhead_s"],
        "p1": stats(p1),
        "p1_vertices": len(last[-1].vertices),
        "p1_dimension": last[-1].dimension,
        "memory_mib": {
            "tracemalloc_peak_p2": traced_peak_mib(lambda: tvmmp(state, witnesses=False)),
            "tracemalloc_peak_p1": None if big else traced_peak_mib(lambda: tvms(state)),
            "ru_maxrss": rss_mib(),
        },
    }


def bench_scaling(
    fingers: Sequence[int] = SCALING_FINGERS,
    *,
    repeats: int = 100,
    p1_repeats: int = 5,
) -> dict[str, Any]:
    """Per hand size: build time, Problem 2 per state (4 RVDS vertices), Problem 1 (RVDS cone), memory."""

    per = {str(f): _scale_one(f, repeats, p1_repeats) for f in fingers}
    keys = list(per)
    ratios = {
        f"{b}/{a}": {
            "fingers": int(b) / int(a),
            "p2_time": per[b]["p2"]["median_s"] / per[a]["p2"]["median_s"],
            "p1_time": per[b]["p1"]["median_s"] / per[a]["p1"]["median_s"],
        }
        for a, b in itertools.pairwise(keys)
    }
    if len(keys) > 1:
        a, b = keys[0], keys[-1]
        ratios[f"{b}/{a}"] = {
            "fingers": int(b) / int(a),
            "p2_time": per[b]["p2"]["median_s"] / per[a]["p2"]["median_s"],
            "p1_time": per[b]["p1"]["median_s"] / per[a]["p1"]["median_s"],
        }
    linear = all(r["p2_time"] <= r["fingers"] for r in ratios.values())
    first, lastf = keys[0], keys[-1]
    exponent = (
        math.log(per[lastf]["p2"]["median_s"] / per[first]["p2"]["median_s"])
        / math.log(int(lastf) / int(first))
        if len(keys) > 1
        else None
    )
    return {
        "hand": "synthetic MJCF (hand_mjcf): bases on a 0.12 m circle, headings inwards, 4 joints per finger, "
        "one fingertip F-contact each, mu 0.5, mg 1 N, RVDS [+-1, +-1, 1, 0, 0, 0]",
        "per_fingers": per,
        "ratios": ratios,
        "p2_at_most_linear": linear,
        "p2_loglog_exponent": exponent,
    }
