r"""The scripted lift (paper section 5, Fig. 7-8): the object's prescribed motion, the
predictor-corrector that keeps the fingers on its surface, and the grasp states along it.
"""

from mjtvm.lift.motion import Motion
from mjtvm.lift.states import READINGS, VARIANTS, lift_state, slide_directions
from mjtvm.lift.trajectory import STOP_MARGIN, Lift, LiftSpec, scripted_lift

__all__ = [
    "READINGS",
    "STOP_MARGIN",
    "VARIANTS",
    "Lift",
    "LiftSpec",
    "Motion",
    "lift_state",
    "scripted_lift",
    "slide_directions",
]
