r"""The paper's four-finger hand (section 5, Fig. 4): its MJCF, the closed-form postures of a
finger on the sphere, and the scenarios of Cases 1 and 2 with the generator of their grasp files.

Imports ``mjtvm.grasp`` (scenarios are grasp files), ``mjtvm.formats`` and MuJoCo;
``mjtvm.polytopes`` only for the Case 1 curve. Everything else (the generator included) is
importable from its module.
"""

from mjtvm.paper_hand.hand import hand_mjcf
from mjtvm.paper_hand.placement import finger1_tvmm_curve, posture_grasp
from mjtvm.paper_hand.scenario import SCENARIOS, load_scenario, read_scenario

__all__ = [
    "SCENARIOS",
    "finger1_tvmm_curve",
    "hand_mjcf",
    "load_scenario",
    "posture_grasp",
    "read_scenario",
]
