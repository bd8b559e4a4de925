r"""The paper's four-finger hand (section 5, Fig. 4): its MJCF, the closed-form postures of a
finger on the sphere, and the scenarios of Cases 1 and 2 with the generator of their grasp files.
"""

from mjtvm.paper_hand.hand import (
    DEFAULT_FINGER_JOINTS,
    HUMANLIKE_FINGER_JOINTS,
    finger_joint_names,
    hand_mjcf,
    model_files,
)
from mjtvm.paper_hand.placement import finger1_tvmm_curve, make_documents, posture_grasp, solve_variant
from mjtvm.paper_hand.posture import FingerGeometry, FingerPosture
from mjtvm.paper_hand.scenario import SCENARIOS, load_scenario, read_scenario, scenario_document

__all__ = [
    "DEFAULT_FINGER_JOINTS",
    "HUMANLIKE_FINGER_JOINTS",
    "SCENARIOS",
    "FingerGeometry",
    "FingerPosture",
    "finger1_tvmm_curve",
    "finger_joint_names",
    "hand_mjcf",
    "load_scenario",
    "make_documents",
    "model_files",
    "posture_grasp",
    "read_scenario",
    "scenario_document",
    "solve_variant",
]
