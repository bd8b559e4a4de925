r"""Benchmarks of hands that mjtvm does not generate: each shipped grasp file of the
test hands through the pipeline a user runs.

Per grasp (``allegro-ik``: the hand-only Allegro, the grasp found by IK; ``allegro-sphere``: the
same hand at a keyframe; ``gripper3-box``: a three-finger gripper and a box on a table):

* **load**: [`load_grasp()`][mjtvm.grasp.resolve.file.load_grasp] (read and check the file, build the model
  with its additions through ``MjSpec``, set the configuration, the IK for ``allegro-ik``);
* **state**: [`state()`][mjtvm.grasp.resolve.loaded.Grasp.state] (contact detection within the tolerance,
  Jacobians, gravity torques);
* **Problem 2**: [`tvmmp()`][mjtvm.problem2.tvmmp.tvmmp] of that state (its RVDS);
* **lift**: [`scripted_lift()`][mjtvm.lift.trajectory.scripted_lift] of the file's ``[lift]``, 30 states.

Medians over repeats after one warm-up.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from benchmarks.measure import stats, times

__all__ = ["HANDS", "bench_hands"]

HANDS = ("allegro-ik", "allegro-sphere", "gripper3-box")


def bench_hands(names: Sequence[str] = HANDS, *, repeats: int = 20, lift_repeats: int = 3) -> dict[str, Any]:
    """``{name: {"joints", "contacts", "load", "state", "p2", "lift": stats}}`` (times in s)."""
    from mjtvm.grasp.resolve.file import load_grasp
    from mjtvm.lift.trajectory import scripted_lift
    from mjtvm.problem2.tvmmp import tvmmp

    out: dict[str, Any] = {}
    for name in names:
        grasp = load_grasp(name)
        state = grasp.state()

        def load(n: str = name) -> object:
            return load_grasp(n)

        def solve(s: Any = state) -> object:
            return tvmmp(s, witnesses=False)

        def lift(g: Any = grasp) -> object:
            return scripted_lift(g, num_states=30)

        out[name] = {
            "joints": len(grasp.joints),
            "contacts": len(state.contacts),
            "rvds": 0 if state.rvds is None else len(state.rvds),
            "load": stats(times(load, max(1, repeats // 4))),
            "state": stats(times(grasp.state, repeats)),
            "p2": stats(times(solve, repeats)),
            "lift": stats(times(lift, lift_repeats)),
        }
    return out
