r"""The MuJoCo coupling, in three rooms: [`mjtvm.sim.grasp`][mjtvm.sim.grasp] (a grasp file and everything it
loads, down to the grasp state), [`mjtvm.sim.lift`][mjtvm.sim.lift] (the scripted lift) and
[`mjtvm.sim.paper_hand`][mjtvm.sim.paper_hand] (the paper's hand and its Cases 1 and 2); [`mjtvm.sim.scene`][mjtvm.sim.scene]
hands the geometry to the viewer.

The names below are imported on first use, so that importing one room (e.g. the viewer's
[`mjtvm.sim.scene`][mjtvm.sim.scene]) does not load the others.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from .._lazy import lazy_attributes

if TYPE_CHECKING:
    from .grasp import DCMotor, Grasp, GraspError, export_state, grasp_state, load_grasp, shipped_grasps
    from .lift import Lift, lift_state, scripted_lift
    from .paper_hand import hand_mjcf, load_scenario
    from .scene import scene_geometry

_HOMES = {
    "DCMotor": "grasp",
    "Grasp": "grasp",
    "GraspError": "grasp",
    "export_state": "grasp",
    "grasp_state": "grasp",
    "load_grasp": "grasp",
    "shipped_grasps": "grasp",
    "Lift": "lift",
    "lift_state": "lift",
    "scripted_lift": "lift",
    "hand_mjcf": "paper_hand",
    "load_scenario": "paper_hand",
    "scene_geometry": "scene",
}

__all__ = [
    "DCMotor",
    "Grasp",
    "GraspError",
    "Lift",
    "export_state",
    "grasp_state",
    "hand_mjcf",
    "lift_state",
    "load_grasp",
    "load_scenario",
    "scene_geometry",
    "scripted_lift",
    "shipped_grasps",
]


__getattr__ = lazy_attributes(__name__, _HOMES)
